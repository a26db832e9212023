#pragma once
// The bijective projection operator of a shell (thesis §4.4; reference-notes §3.5).
//
// Prism coordinates (face, u, v, h): (u, v) are barycentric coordinates in the face rotated so
// that its smallest vertex id is local 0 (point = (1-u-v)·c0 + u·c1 + v·c2), h ∈ [-1, 1] goes from
// base (-1) through the middle surface (0) to top (1), piecewise linearly over the canonical
// 3-tet split of each half-prism. A fiber is the set of points with fixed (face, u, v): a
// polyline through the 4 rising facets of each half. P maps a shell point to the input point
// on its fiber; P⁻¹ maps an input point to its prism coordinates. Point location uses exact
// orientation predicates; intersections are decided by exact predicates and only then solved
// for barycentric coordinates.
//
// P projects onto the surface given to the constructor, which need not be the shell's input: any
// section of the shell will do (thesis Fig. 4.7). Two projections of one shell onto sections S1
// and S2 compose to the bijection S1 → S2 (section_transfer.hpp). The surface is copied; the
// shell must outlive the object. Queries are const and thread-safe.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::meshing::shell {

struct PrismPoint {
  int face = -1;
  double u = 0, v = 0, h = 0;
};

struct SurfacePoint {
  int face = -1;                  // input face
  Eigen::Vector3d bary{0, 0, 0};  // barycentric coordinates in that face (input vertex order)
  Eigen::Vector3d position{0, 0, 0};
};

class ShellProjection {
 public:
  ShellProjection(const Shell& shell, const SurfaceMesh& input);
  ~ShellProjection();

  bool is_inside(const Eigen::Vector3d& p) const { return locate(p).has_value(); }
  // The prism coordinates of a point of the shell (nullopt outside). A pinch point (the corner
  // of a zero-length pillar, base = mid = top) gets exactly that corner's (u, v) and h = 0.
  std::optional<PrismPoint> locate(const Eigen::Vector3d& p) const;
  // The physical point of prism coordinates.
  Eigen::Vector3d point(const PrismPoint& q) const;
  // P_T: the input point on the fiber of (face, u, v). At a pinch corner the fiber is the pinch
  // point: its input point. Near one, where the rounded fiber is too short for the exact search,
  // the crossing is solved on the fiber scaled up about the pinch point (projection.cpp).
  std::optional<SurfacePoint> project(const PrismPoint& q) const;
  // P: a point of the shell to the input.
  std::optional<SurfacePoint> project(const Eigen::Vector3d& p) const;
  // P⁻¹: an input point to its prism coordinates (h tells where it sits between base and top).
  std::optional<PrismPoint> unproject(const Eigen::Vector3d& input_point) const;
  // P⁻¹ of a point of input face `input_face`. A locally injective shell (Shell::local_sheets)
  // needs the face: where the input passes through itself a point lies in the prisms of each
  // sheet there, and only those whose local sheet holds the face map it back to it (P crosses
  // each prism's fibers with its local sheet only). Otherwise the same as above.
  std::optional<PrismPoint> unproject(const Eigen::Vector3d& input_point, int input_face) const;

  // The fiber of (face, u, v) from base to top: its 7 corners on the rising facets of the two
  // halves (index 3 is on the middle triangle). Straight between consecutive corners.
  std::array<Eigen::Vector3d, 7> fiber(int face, double u, double v) const;
  // Prisms whose bounding box meets the box [lo, hi] (a superset of the prisms meeting it).
  std::vector<int> prisms_in_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  const Shell& shell() const;
  // With a reference copy (Shell::reference, feature chains) P crosses the fibers with that copy
  // and reports the input point of the same face and barycentric coordinates, so P composes the
  // shell's projection with the copy's correspondence to the input; locate and unproject take
  // points of the copy, whose vertices these are (the input's vertices without one).
  const Eigen::MatrixXd& reference_vertices() const;
  // is_section(T) of thesis §4.4: is the closed triangle mesh m a section of the shell (every
  // fiber crosses it exactly once, transversally)? What is checked: section.hpp.
  bool is_section(const SurfaceMesh& m) const;

 private:
  // locate, restricted to prisms whose local sheet holds input_face (>= 0, local sheets only).
  std::optional<PrismPoint> locate_on(const Eigen::Vector3d& p, int input_face) const;
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace curvefem::meshing::shell
