// Triangle surface mesh: the dense input of every curvefem pipeline.
//
// V is #V × 3 (double), F is #F × 3 (0-based vertex ids). A valid input for meshing is closed,
// manifold, oriented outward (counter-clockwise seen from outside, positive signed volume) and free
// of self-intersections: meshing/check decides that; this type holds any triangle soup.
// tags is empty or #F: an integer per face (OBJ group / usemtl, PLY face property, MSH physical
// tag); tag_names optionally names tag values (OBJ group names, MSH physical names).
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <utility>

namespace curvefem {

struct SurfaceMesh {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Eigen::VectorXi tags;
  std::map<int, std::string> tag_names;

  int num_vertices() const { return static_cast<int>(V.rows()); }
  int num_faces() const { return static_cast<int>(F.rows()); }
  bool has_tags() const { return tags.size() == F.rows() && F.rows() > 0; }
};

/// Longest edge of the axis-aligned bounding box (the unit of every `*_rel` figure); 0 if empty.
double bbox_longest_edge(const Eigen::MatrixXd& V);

/// The exterior box of a surface: the bounding box of V widened on every side by padding_rel ×
/// its longest edge (`meshing.padding`, `curvefem mesh --padding`), as {lo, hi}.
std::pair<Eigen::Vector3d, Eigen::Vector3d> padded_bounding_box(const Eigen::MatrixXd& V,
                                                                double padding_rel);

/// Signed volume enclosed by the triangles (positive for a closed outward surface).
double signed_volume(const SurfaceMesh& mesh);

}  // namespace curvefem
