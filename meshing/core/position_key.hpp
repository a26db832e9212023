// Exact keys of 3-D points, for finding the same point again by value (the bit patterns of its
// three doubles, -0.0 taken as 0.0): a node of one mesh at a vertex of another, coincident
// vertices. PositionHash makes them usable in std::unordered_map; the array compares for
// std::map and sorting.
#pragma once

#include <Eigen/Core>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

namespace curvefem {

struct PositionKey {
  std::array<std::uint64_t, 3> bits{};
  bool operator==(const PositionKey&) const = default;
  auto operator<=>(const PositionKey&) const = default;
};

struct PositionHash {
  std::size_t operator()(const PositionKey& k) const {
    return k.bits[0] * 0x9E3779B97F4A7C15ull ^ (k.bits[1] + 0x7F4A7C15ull) * 31 ^ k.bits[2];
  }
};

inline PositionKey position_key(double x, double y, double z) {
  auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v == 0.0 ? 0.0 : v); };
  return {{bits(x), bits(y), bits(z)}};
}

template <typename Derived>
PositionKey position_key(const Eigen::MatrixBase<Derived>& p) {
  return position_key(double(p(0)), double(p(1)), double(p(2)));
}

}  // namespace curvefem
