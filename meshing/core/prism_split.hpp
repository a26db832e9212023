#pragma once
// Index conventions of shell prisms, shared by the shell's construction, projection and
// verification (meshing/shell) and by the saved fibers of a shell (shell_fibers.hpp), whose
// evaluation must follow the same polylines (reference-notes §3.5, §10.1): a face is rotated so
// that its smallest vertex id comes first; it is "type A" when its second id is larger than its
// third. The canonical 3-tet split of each half-prism (base corners 0..2, top corners 3..5 in
// rotated order) then joins, on every side quad, the base of the lower global id to the top of the
// higher one, so neighbours conform (DESIGN.md §2, "Prism, split, validity").

#include <Eigen/Core>
#include <algorithm>
#include <array>

namespace curvefem {

// Rotation r such that (f[r], f[r+1], f[r+2]) starts at the smallest id.
inline int min_rotation(const Eigen::Vector3i& f) {
  return (f[0] < f[1] && f[0] < f[2]) ? 0 : (f[1] < f[2] ? 1 : 2);
}
inline bool is_type_a(const Eigen::Vector3i& f) {
  const int r = min_rotation(f);
  return f[(r + 1) % 3] > f[(r + 2) % 3];
}
// The 3 tets of the canonical split (corners in rotated order: base 0..2, top 3..5).
inline const std::array<std::array<int, 4>, 3>& split_tets(bool type_a) {
  static const std::array<std::array<int, 4>, 3> a{{{0, 3, 4, 5}, {1, 4, 2, 0}, {2, 5, 0, 4}}};
  static const std::array<std::array<int, 4>, 3> b{{{0, 3, 4, 5}, {1, 4, 5, 0}, {2, 5, 0, 1}}};
  return type_a ? a : b;
}
// The 4 "rising facets" of the split, bottom to top: a fiber at (u, v) crosses them in order.
inline const std::array<std::array<int, 3>, 4>& rising_facets(bool type_a) {
  static const std::array<std::array<int, 3>, 4> a{{{0, 1, 2}, {0, 4, 2}, {0, 4, 5}, {3, 4, 5}}};
  static const std::array<std::array<int, 3>, 4> b{{{0, 1, 2}, {0, 1, 5}, {0, 4, 5}, {3, 4, 5}}};
  return type_a ? a : b;
}

// The 7 corners of the fiber at barycentric weights w (rotated order) on the rising facets of
// both halves, bottom to top (index 3 on the middle triangle). corner(half, c) is corner c
// (0..2 lower, 3..5 upper, rotated order) of half-prism `half` (0: base-mid, 1: mid-top).
template <class Corner>
std::array<Eigen::Vector3d, 7> fiber_points(bool type_a, const std::array<double, 3>& w,
                                            const Corner& corner) {
  std::array<Eigen::Vector3d, 7> out;
  int n = 0;
  for (int half = 0; half < 2; ++half)
    for (int i = half; i < 4; ++i) {  // the mid facet of half 1 is the top facet of half 0
      std::array<int, 3> sorted = rising_facets(type_a)[i];
      std::sort(sorted.begin(), sorted.end(), [](int a, int b) { return a % 3 < b % 3; });
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) x += w[k] * corner(half, sorted[k]);
      out[n++] = x;
    }
  return out;
}
// Fiber segments (a, b) of fiber_points in search order: from the middle (index 3) outwards,
// where the input crosses the fiber near h = 0.
inline constexpr int k_fiber_walk[6][2] = {{3, 2}, {3, 4}, {2, 1}, {4, 5}, {1, 0}, {5, 6}};

}  // namespace curvefem
