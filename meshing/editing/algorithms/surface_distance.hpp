#pragma once
// Distance queries to a fixed triangle surface (CGAL AABB tree behind a pimpl, so no CGAL in
// headers). Queries are const and thread-safe after construction.

#include <Eigen/Core>
#include <memory>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::meshing::editing {

class SurfaceDistance {
 public:
  // V: #V x 3, F: #F x 3 (the surface is copied).
  SurfaceDistance(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
  ~SurfaceDistance();
  SurfaceDistance(const SurfaceDistance&) = delete;
  SurfaceDistance& operator=(const SurfaceDistance&) = delete;

  double squared_distance(const Eigen::Vector3d& p) const;
  Eigen::Vector3d closest_point(const Eigen::Vector3d& p) const;

  // Conservative envelope test (see surface_remeshing.hpp): true only if every point of the
  // triangle (a, b, c) is within eps of the surface.
  bool triangle_within(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       double eps) const;
  // Largest distance over a barycentric sampling of the triangle with `n` subdivisions.
  double max_distance_sampled(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c, int n) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace curvefem::meshing::editing
