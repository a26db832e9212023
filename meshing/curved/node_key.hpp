// The identity of a Lagrange node shared between cells: the multiset of the global corner ids it
// is a lattice point of (each id repeated by its multi-index entry, sorted, padded with the
// largest id), the same point of the same sub-simplex in any cell. Used by the stitching
// (curved_mesher.cpp) and the curved edits (curved_edit.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <vector>

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

/// Node keys to node ids, by open addressing (linear probing, a power-of-two table at most half
/// full, a multiply-xorshift hash): the curved edits look nodes up for most lattice points of
/// every cell they try, where std::unordered_map's bucket lists cost a cache miss more per
/// lookup. Nothing is ever erased.
template <class Id>
class NodeKeyMap {
 public:
  /// The id of `key`, or nullptr.
  const int* find(const NodeKey<Id>& key) const {
    if (m_slots.empty()) return nullptr;
    const Slot& s = m_slots[probe(key)];
    return s.used ? &s.value : nullptr;
  }
  int at(const NodeKey<Id>& key) const {
    const int* v = find(key);
    if (!v) throw std::out_of_range("NodeKeyMap::at: no node for this key");
    return *v;
  }
  /// Adds key -> value unless key is there; returns the id kept and whether it was added.
  std::pair<int, bool> insert(const NodeKey<Id>& key, int value) {
    reserve_one();
    Slot& s = m_slots[probe(key)];
    if (s.used) return {s.value, false};
    s = Slot{key, value, true};
    ++m_size;
    return {value, true};
  }
  /// key -> value, added or replaced.
  void assign(const NodeKey<Id>& key, int value) {
    reserve_one();
    Slot& s = m_slots[probe(key)];
    if (!s.used) ++m_size;
    s = Slot{key, value, true};
  }
  std::size_t size() const { return m_size; }

 private:
  struct Slot {
    NodeKey<Id> key{};
    int value = 0;
    bool used = false;
  };
  static std::uint64_t hash(const NodeKey<Id>& key) {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (Id x : key.id) {
      h ^= std::uint64_t(x);
      h *= 0xBF58476D1CE4E5B9ull;
      h ^= h >> 31;
    }
    return h;
  }
  // The slot holding key, or the empty slot where it would go.
  std::size_t probe(const NodeKey<Id>& key) const {
    const std::size_t mask = m_slots.size() - 1;
    std::size_t i = std::size_t(hash(key)) & mask;
    while (m_slots[i].used && !(m_slots[i].key == key)) i = (i + 1) & mask;
    return i;
  }
  void reserve_one() {
    if (2 * (m_size + 1) <= m_slots.size()) return;
    std::vector<Slot> old = std::move(m_slots);
    m_slots.assign(std::max<std::size_t>(64, 2 * old.size()), Slot{});
    m_size = 0;
    for (const Slot& s : old)
      if (s.used) {
        m_slots[probe(s.key)] = s;
        ++m_size;
      }
  }

  std::vector<Slot> m_slots;
  std::size_t m_size = 0;
};

}  // namespace curvefem::meshing::curved
