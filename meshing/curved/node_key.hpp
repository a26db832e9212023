// The identity of a Lagrange node shared between cells: the multiset of the global corner ids it
// is a lattice point of (each id repeated by its multi-index entry, sorted, padded with the
// largest id), the same point of the same sub-simplex in any cell. Used by the stitching
// (curved_mesher.cpp) and the curved edits (curved_edit.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <compare>
#include <cstddef>
#include <functional>
#include <limits>

namespace curvefem::meshing::curved {

template <class Id>
struct NodeKey {
  std::array<Id, 4> id;
  auto operator<=>(const NodeKey&) const = default;
};

template <class Id>
struct NodeKeyHash {
  std::size_t operator()(const NodeKey<Id>& k) const {
    std::size_t h = 0;
    for (Id x : k.id) h = h * 1000003u ^ std::hash<Id>()(x);
    return h;
  }
};

/// Key of the lattice point alpha (multi-index over the first `corners` ids of `gid`).
template <class Id>
NodeKey<Id> make_node_key(const Id* gid, const std::array<int, 4>& alpha, int corners) {
  NodeKey<Id> key;
  key.id.fill(std::numeric_limits<Id>::max());
  int n = 0;
  for (int j = 0; j < corners; ++j)
    for (int m = 0; m < alpha[std::size_t(j)]; ++m) key.id[std::size_t(n++)] = gid[j];
  std::sort(key.id.begin(), key.id.begin() + n);
  return key;
}

}  // namespace curvefem::meshing::curved
