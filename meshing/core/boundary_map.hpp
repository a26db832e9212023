// The boundary map φ between a dense input surface M and the curved boundary ∂T^k of a tet mesh
// (DESIGN.md §2): for every input vertex v, the boundary triangle of T^k and the reference
// coordinates (u, v) in it such that the curved triangle evaluated there is φ(v).
//
// `boundary` is a triangle LagrangeMesh of the same order as the volume mesh whose cells are the
// boundary faces of the volume mesh, with its own copy of the nodes (so the map is self-contained
// and serializable without the volume); `boundary_node_to_volume` gives, for each of its nodes,
// the node of the volume mesh it is (#boundary nodes, -1 if not tied to a volume).
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem {

struct BoundaryMap {
  LagrangeMesh boundary;  // kind = triangle, order k
  Eigen::VectorXi boundary_node_to_volume;
  Eigen::VectorXi vertex_face;  // #input V: boundary triangle of φ(v), -1 for unreferenced vertices
  Eigen::MatrixXd vertex_uv;    // #input V × 2: reference coordinates (ξ, η) in that triangle
  // Distance points besides the input vertices (optional; constraint points and samples where the
  // mesher enforced ε): the input point (input face, barycentric coordinates in input vertex
  // order) and the boundary triangle and (ξ, η) of its image.
  Eigen::VectorXi point_input_face;
  Eigen::MatrixXd point_bary;  // #points × 3
  Eigen::VectorXi point_face;
  Eigen::MatrixXd point_uv;  // #points × 2

  // Input feature edges (input vertex pairs) the mesh keeps as curved feature edges: both ends
  // of each map onto one boundary edge (the validator checks it). Empty: no features.
  std::vector<std::array<int, 2>> feature_edges;

  // Spatially varying ε (issue 22): empty (one ε everywhere), or #input V factors in (0, 1]: the
  // distance bound at input vertex v is ε · eps_scale[v], and at a point inside an input face
  // the barycentric interpolation of its corners' factors (the validator checks both).
  std::vector<double> eps_scale;
  /// The factor at input face t, barycentric coordinates w (1 without a field).
  double eps_scale_at(int t, const Eigen::Vector3d& w, const Eigen::MatrixXi& input_faces) const;

  int num_points() const { return static_cast<int>(point_face.size()); }
  /// The image of distance point i.
  Eigen::Vector3d point_image(int i) const;

  int num_input_vertices() const { return static_cast<int>(vertex_face.size()); }
  /// φ(v): the curved boundary triangle evaluated at the vertex's coordinates.
  Eigen::Vector3d image(int input_vertex) const;
};

/// Throws InputError naming the first structural defect (sizes, ids, coordinates outside the
/// reference triangle by more than `uv_tolerance`). Input face ids of distance points are checked
/// against the input by the validator (the map does not know the input).
void validate_structure(const BoundaryMap& map, double uv_tolerance = 1e-9);

}  // namespace curvefem
