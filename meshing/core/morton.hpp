// Morton (Z-order) keys of points, 21 bits per axis: nearby points get nearby keys, so sorting by
// key gives a spatially local order (the editing scheduler's partitions, fem's DOF numbering).
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace curvefem {

/// The low 21 bits of v, spread to every third bit.
inline std::uint64_t morton_spread(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

/// The key of p in the cube [lo, lo + extent]³ (extent > 0; p inside the cube).
inline std::uint64_t morton_key(const Eigen::Vector3d& p, const Eigen::Vector3d& lo,
                                double extent) {
  const Eigen::Vector3d q = (p - lo) / extent * double((1 << 21) - 1);
  return morton_spread(std::uint64_t(q.x())) | morton_spread(std::uint64_t(q.y())) << 1 |
         morton_spread(std::uint64_t(q.z())) << 2;
}

}  // namespace curvefem
