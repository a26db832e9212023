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
//   outer_box [side]         exterior runs: the points of the padded outer box, all of it
//                            (side -1) or one side (0..5 = x min, x max, y min, y max, z min,
//                            z max)
//
// Points of an exterior run's boundary are either on the input surface (through φ⁻¹) or on the
// outer box. A selection whose tree has no outer_box never selects a box point (selects_point);
// one that has is evaluated on box points too, where all, tag and normal are false (they describe
// the input surface) and box, plane are tested at the point.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "mapping/boundary_inverse.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::mapping {

struct Selection {
  enum class Kind { all, tag, box, plane, normal, all_of, any_of, none_of, outer_box };
  Kind kind = Kind::all;
  int tag = 0;
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // box
  Eigen::Vector3d point = Eigen::Vector3d::Zero();                             // plane
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // plane normal / normal-cone axis
  double angle_deg = 0;                                  // normal cone half-angle
  int box_side = -1;                                     // outer_box: -1 all, 0..5 one side
  std::vector<Selection> children;                       // and / or: ≥ 1; not: exactly 1
  std::string where;                                     // JSON path, for messages
};

/// What a selection looks at: the point, the tag of its input face (-1 if none) and the face's
/// outward unit normal.
struct SelectionSite {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  int tag = -1;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  int box_side = -1;  ///< -1: a point of the input surface; 0..5: of that side of the outer box
};

/// The selection tree evaluated at a site (the rules above, without the top-level one).
bool selects(const Selection& s, const SelectionSite& site);
/// As selects, except that a selection without outer_box never selects a box point.
bool selects_point(const Selection& s, const SelectionSite& site);

/// Whether a selection names outer_box anywhere in its tree.
bool uses_outer_box(const Selection& s);

/// Names of the outer box's sides, by index: "xmin", "xmax", "ymin", "ymax", "zmin", "zmax".
const char* box_side_name(int side);

/// The side of the axis-aligned box [lo, hi] that x lies on (within tol; the first in index order
/// at an edge or corner), or -1.
int box_side_of(const Eigen::Vector3d& x, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                double tol);

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
