// Charts of a triangle surface: the surface cut along seams (and OBJ group borders) into
// disk-topology pieces, each to be mapped bijectively into the plane (thesis §3.2.2, §3.3).
//
// A *UV vertex* is one fan of face corners around an input vertex: corners of two faces sharing
// an edge belong to the same UV vertex unless the edge is cut (a seam, a border between groups,
// or a mesh boundary). A vertex on a seam therefore has several UV vertices (several `vt` in the
// OBJ output). A *chart* is a connected component of faces glued along uncut edges.
//
// Conventions: F keeps the input's face order and orientation; UV vertex ids are numbered by
// first appearance in F. Every chart must be an oriented disk: Euler characteristic V − E + F = 1
// and exactly one boundary loop, else InputError naming the chart, its group and both numbers.
// boundary_loops[c] lists chart c's boundary UV vertices in the direction of the faces' own
// half-edges (interior on the left: counter-clockwise once the chart is embedded positively).
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::meshing::param {

struct CutMesh {
  Eigen::MatrixXd V;       ///< #U × 3: 3D position of each UV vertex (that of its parent)
  Eigen::VectorXi parent;  ///< #U: input vertex id of each UV vertex
  Eigen::MatrixXi F;       ///< #F × 3: faces in UV vertex ids (input order and orientation)
  Eigen::VectorXi chart;   ///< #F: chart id in 0 .. num_charts − 1
  int num_charts = 0;
  std::vector<std::vector<int>> boundary_loops;  ///< per chart: its single boundary loop
  std::vector<std::string> chart_names;          ///< per chart: "chart c (group 'name')" text

  int num_uv_vertices() const { return static_cast<int>(V.rows()); }
  int num_faces() const { return static_cast<int>(F.rows()); }
};

struct CutOptions {
  /// Faces with different tags (OBJ groups) are never glued: each group is its own chart(s).
  bool split_groups = true;
};

/// Cuts `mesh` along `seams` (pairs of 0-based input vertex ids, each an edge of the mesh) and
/// along group borders. Throws InputError for: a seam that is not an edge, a degenerate face
/// (repeated vertex or zero 3D area), a non-manifold edge, two faces of an edge with the same
/// orientation, a chart that is not a disk.
CutMesh cut_into_charts(const SurfaceMesh& mesh, const std::vector<std::array<int, 2>>& seams,
                        const CutOptions& options = {});

/// Rest shape of each face: its 3D area (#F), and the 3 × 2 matrix G_f of the gradients of its
/// barycentric coordinates in an isometric 2D frame of the 3D triangle, so that the Jacobian of
/// the map to the plane with corner images q_0, q_1, q_2 (rows of Q, 3 × 2) is J = Qᵀ G_f.
struct RestShapes {
  std::vector<Eigen::Matrix<double, 3, 2>> G;
  Eigen::VectorXd area;
};
RestShapes rest_shapes(const CutMesh& cut);

}  // namespace curvefem::meshing::param
