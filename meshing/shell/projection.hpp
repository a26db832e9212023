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

#include <Eigen/Core>
#include <memory>
#include <optional>

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
  // The prism coordinates of a point of the shell (nullopt outside).
  std::optional<PrismPoint> locate(const Eigen::Vector3d& p) const;
  // The physical point of prism coordinates.
  Eigen::Vector3d point(const PrismPoint& q) const;
  // P_T: the input point on the fiber of (face, u, v).
  std::optional<SurfacePoint> project(const PrismPoint& q) const;
  // P: a point of the shell to the input.
  std::optional<SurfacePoint> project(const Eigen::Vector3d& p) const;
  // P⁻¹: an input point to its prism coordinates (h tells where it sits between base and top).
  std::optional<PrismPoint> unproject(const Eigen::Vector3d& input_point) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace curvefem::meshing::shell
