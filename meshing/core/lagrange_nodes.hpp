// Canonical local node order of Lagrange simplices of order k = 1..4 (triangles and tetrahedra),
// used by every curvefem mesh, basis and file format adapter.
//
// Reference simplex: v0 = origin, v1 = e_x, v2 = e_y (, v3 = e_z). A node is a lattice point with
// barycentric multi-index α (α_0 + ... + α_d = k); its reference coordinates are (α_1, .., α_d)/k.
//
// Canonical order (the one documented rule; no per-order tables):
//   1. group nodes by their *entity* — the set of vertices i with α_i > 0;
//   2. entities by dimension (vertices, edges, faces, interior), equal dimension in lexicographic
//      order of their sorted vertex lists: edges (0,1) (0,2) (0,3) (1,2) (1,3) (2,3); faces
//      (0,1,2) (0,1,3) (0,2,3) (1,2,3);
//   3. inside an entity, descending lexicographic order of α — an edge (a,b) is walked from a to b.
// File formats (VTK, Gmsh) use other orders; their permutations are built by matching reference
// coordinates (meshing/io), never written by hand.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

namespace curvefem {

enum class CellKind { triangle, tetrahedron };

constexpr int k_max_order = 4;

/// 2 for triangles, 3 for tetrahedra.
int cell_dimension(CellKind kind);
/// (k+1)(k+2)/2 for triangles, (k+1)(k+2)(k+3)/6 for tetrahedra.
int num_lagrange_nodes(CellKind kind, int order);
/// Inverse of num_lagrange_nodes; -1 when n is not a node count of an order-1..10 simplex.
int order_from_node_count(CellKind kind, int n);

/// Barycentric multi-indices in canonical order (triangles use entries 0..2, entry 3 is 0).
const std::vector<std::array<int, 4>>& lagrange_lattice(CellKind kind, int order);
/// #nodes × dim reference coordinates in canonical order.
Eigen::MatrixXd lagrange_reference_nodes(CellKind kind, int order);

/// Values of the equispaced Lagrange basis of `order` at reference point `xi` (dim entries used).
Eigen::VectorXd lagrange_shape_values(CellKind kind, int order, const Eigen::Vector3d& xi);
/// #nodes × dim reference gradients of the same basis.
Eigen::MatrixXd lagrange_shape_gradients(CellKind kind, int order, const Eigen::Vector3d& xi);

/// Parametric shape of an order-k Lagrange triangle in space (nodes in canonical order): the
/// smallest area element |x_ξ × x_η| over the points of its order-4k lattice, over the largest;
/// a point where the normal x_ξ × x_η turns against the plane of the corners counts as 0 (the
/// patch folds). 1 for a straight triangle. Used by the mesher to lower the curving of distorted
/// patches (the validator has its own).
double triangle_area_element_ratio(int order, const std::vector<Eigen::Vector3d>& nodes);

}  // namespace curvefem
