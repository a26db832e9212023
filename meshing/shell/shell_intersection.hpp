#pragma once
// Exact queries against the input surface used by shell construction and verification (CGAL
// AABB tree and filtered exact predicates behind a pimpl).

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

namespace curvefem::meshing::shell {

class InputSurfaceIndex {
 public:
  InputSurfaceIndex(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
  ~InputSurfaceIndex();
  InputSurfaceIndex(const InputSurfaceIndex&) = delete;
  InputSurfaceIndex& operator=(const InputSurfaceIndex&) = delete;

  // Distance from `origin` along the unit `direction` to the first input face not in `ignore`
  // (+infinity when the ray leaves without hitting).
  double ray_distance(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                      const std::vector<int>& ignore) const;

  // Does the triangle intersect the input? Triangle corner k with singular[k] lies on the input
  // at input vertex `corner_ids[k]` (a pinch point): contact at that point alone is allowed
  // (tested exactly with the opposite edges, no constructed points).
  bool triangle_intersects(const std::array<Eigen::Vector3d, 3>& triangle,
                           const std::array<bool, 3>& singular,
                           const Eigen::Vector3i& corner_ids) const;

  // Input faces whose triangle intersects the (closed) tetrahedron (exact).
  std::vector<int> faces_touching_tet(const std::array<Eigen::Vector3d, 4>& tet) const;

  // Input faces whose bounding box overlaps [lo, hi] (a superset of the faces meeting the box).
  std::vector<int> faces_in_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  // Does input face f intersect the closed tetrahedron (exact)?
  bool face_touches_tet(int f, const std::array<Eigen::Vector3d, 4>& tet) const;

  // Closest input point: face id and the point.
  int closest_face(const Eigen::Vector3d& p, Eigen::Vector3d& closest) const;

  // First input face hit by segment [a, b] (exact do_intersect for the candidates, closest to a
  // by a barycentric solve); -1 if none. bary receives the barycentric coordinates of the hit in
  // that face.
  int segment_hit(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Eigen::Vector3d& bary) const;

  const Eigen::MatrixXd& V() const;
  const Eigen::MatrixXi& F() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace curvefem::meshing::shell
