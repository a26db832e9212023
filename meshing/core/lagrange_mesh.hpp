// Mesh of Lagrange simplices of geometric order k = 1..4: curved tetrahedra (volume meshes) or
// curved triangles (boundary surfaces), with nodes shared between neighbouring cells.
//
// nodes: #N × 3. cells: #C × num_lagrange_nodes(kind, order), each row the global node ids of one
// cell in the canonical local order of lagrange_nodes.hpp. cell_tags: empty or #C.
// A positively oriented tetrahedron has det(x1-x0, x2-x0, x3-x0) > 0 at its vertices.
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "meshing/core/lagrange_nodes.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem {

struct LagrangeMesh {
  CellKind kind = CellKind::tetrahedron;
  int order = 1;
  Eigen::MatrixXd nodes;
  Eigen::MatrixXi cells;
  Eigen::VectorXi cell_tags;

  int num_nodes() const { return static_cast<int>(nodes.rows()); }
  int num_cells() const { return static_cast<int>(cells.rows()); }
  int nodes_per_cell() const { return num_lagrange_nodes(kind, order); }

  /// Geometric map of `cell` at reference point xi (z ignored for triangles).
  Eigen::Vector3d map(int cell, const Eigen::Vector3d& xi) const;
  /// 3 × dim Jacobian of the geometric map at xi.
  Eigen::MatrixXd jacobian(int cell, const Eigen::Vector3d& xi) const;
};

/// Bounding box {lo, hi} of the cells' vertices (corner nodes) of a tet mesh: a higher-order node
/// on a flat face, a weighted mean of the face's corners, can round past them.
std::pair<Eigen::Vector3d, Eigen::Vector3d> vertex_bounding_box(const LagrangeMesh& mesh);

/// Throws InputError naming the first defect: bad order, wrong column count, node id out of
/// range, non-finite coordinate, tag count mismatch.
/// A triangle surface as an order-1 triangle LagrangeMesh (nodes = V, cells = F, cell_tags = the
/// face tags), e.g. for write_vtu.
LagrangeMesh as_triangle_mesh(const SurfaceMesh& s);

void validate_structure(const LagrangeMesh& mesh, const std::string& what = "mesh");

/// A named field attached to points (nodes) or cells; values are row-major, size n × components.
struct Field {
  std::string name;
  int components = 1;
  std::vector<double> values;
};

struct MeshFields {
  std::vector<Field> point_data;
  std::vector<Field> cell_data;
};

}  // namespace curvefem
