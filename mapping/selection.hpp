// Selections of boundary regions, evaluated on the dense input surface at a point of an input face
// (DESIGN.md §4; issue 7). They act point-wise: a face partly covered by a box, a plane side or a
// combination is selected exactly at the points the selection covers, never per coarse face.
//
// Kinds:
//   all                      every point
//   tag N                    points of input faces whose tag is N (SurfaceMesh::tags; none if the
//                            input carries no tags)
//   box [lo, hi]             lo ≤ x ≤ hi component-wise (closed)
//   plane {point, normal}    (x − point)·normal ≥ 0: the side the normal points to (closed)
//   normal {direction, deg}  the input face's outward unit normal n makes an angle ≤ deg with
//                            direction (n·d ≥ cos(deg)·|d|)
//   and / or [S...]          all / any of the children; not S: the complement
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mapping/boundary_inverse.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::mapping {

struct Selection {
  enum class Kind { all, tag, box, plane, normal, all_of, any_of, none_of };
  Kind kind = Kind::all;
  int tag = 0;
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // box
  Eigen::Vector3d point = Eigen::Vector3d::Zero();                             // plane
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // plane normal / normal-cone axis
  double angle_deg = 0;                                  // normal cone half-angle
  std::vector<Selection> children;                       // and / or: ≥ 1; not: exactly 1
  std::string where;                                     // JSON path, for messages
};

/// What a selection looks at: the point, the tag of its input face (-1 if none) and the face's
/// outward unit normal.
struct SelectionSite {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  int tag = -1;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

bool selects(const Selection& s, const SelectionSite& site);

/// The site of a point of the input (face tag and face normal from `input`).
SelectionSite site_of(const SurfaceMesh& input, const InputPoint& p);
/// Outward unit normal of input face f (zero for a degenerate face).
Eigen::Vector3d face_normal(const SurfaceMesh& input, int f);

/// Whether a selection uses face data (tag or normal) anywhere in its tree.
bool uses_face_data(const Selection& s);

/// Share of the 4 samples of input face f (3 corners and the centroid) that `s` selects: 0, 0.25,
/// ..., 1 (for surface.vtu: 1 = fully selected, 0 = not at all, between = partly covered).
double face_coverage(const Selection& s, const SurfaceMesh& input, int f);

}  // namespace curvefem::mapping
