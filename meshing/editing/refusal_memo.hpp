#pragma once
// Refused edge operations (v -> w) remembered so that a pass can skip them while nothing they
// read has changed. The user stamps, after every accepted operation, the corners of the cells it
// removed, created or reshaped (`stamp`, inside the operation: the stamps are journaled); a
// refusal is kept with the clock at the time and a payload (why it was refused, what it flagged).
// `replay(v, w)` gives the payload back while no corner of a cell around v or w carries a later
// stamp. That this means "the checks would refuse again" is the user's argument: it holds when
// the checks read only the cells around v and w, cells sharing a face or an edge with them (whose
// corners are among theirs) and data that does not change during the pass.
// Several kinds of operation on one edge (a collapse, the swaps of a face or an edge through it)
// are told apart by a `tag` the user picks (0 for the plain v -> w). Stamping may run on several
// threads (each on the vertices it has locked); remember/replay are for one-thread passes (the
// lists are not locked).

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <initializer_list>
#include <vector>

#include "meshing/editing/attribute.hpp"
#include "meshing/editing/simplex_mesh.hpp"

namespace curvefem::meshing::editing {

template <class Mesh, class Payload>
class RefusalMemo {
 public:
  explicit RefusalMemo(Mesh& mesh) : m_mesh(mesh), m_changed(mesh, 0, 0) {}

  // After an accepted operation: a fresh clock value on every corner of these cells.
  void stamp(std::initializer_list<const std::vector<Id>*> cell_lists) {
    const std::uint64_t now = m_clock.fetch_add(1, std::memory_order_relaxed) + 1;
    for (const auto* cells : cell_lists)
      for (Id c : *cells)
        for (Id u : m_mesh.cell(c)) m_changed.set(u, now);
  }
  void remember(Id v, Id w, const Payload& payload, std::uint64_t tag = 0) {
    if (m_refusals.size() <= std::size_t(v)) m_refusals.resize(std::size_t(v) + 1);
    auto& list = m_refusals[std::size_t(v)];
    const Entry e{w, tag, m_clock.load(std::memory_order_relaxed), payload};
    const auto it = std::find_if(list.begin(), list.end(),
                                 [w, tag](const Entry& x) { return x.to == w && x.tag == tag; });
    if (it != list.end())
      *it = e;
    else
      list.push_back(e);
  }
  // The payload of v -> w's refusal while nothing around v and w changed since (a stale entry is
  // dropped); nullptr otherwise.
  const Payload* replay(Id v, Id w, std::uint64_t tag = 0) {
    if (std::size_t(v) >= m_refusals.size()) return nullptr;
    auto& list = m_refusals[std::size_t(v)];
    const auto it = std::find_if(list.begin(), list.end(),
                                 [w, tag](const Entry& x) { return x.to == w && x.tag == tag; });
    if (it == list.end()) return nullptr;
    if (std::max(latest_change_near(v), latest_change_near(w)) > it->at) {
      list.erase(it);
      return nullptr;
    }
    ++m_replayed;
    return &it->payload;
  }
  void forget_all() { m_refusals.clear(); }
  long replayed() const { return m_replayed; }

 private:
  struct Entry {
    Id to = k_no_id;
    std::uint64_t tag = 0;
    std::uint64_t at = 0;
    Payload payload;
  };
  std::uint64_t latest_change_near(Id v) const {
    std::uint64_t t = m_changed[v];
    for (Id c : m_mesh.vertex_cells(v))
      for (Id u : m_mesh.cell(c)) t = std::max(t, m_changed[u]);
    return t;
  }

  Mesh& m_mesh;
  Attribute<std::uint64_t> m_changed;
  std::atomic<std::uint64_t> m_clock{0};
  std::vector<std::vector<Entry>> m_refusals;  // per removed vertex
  long m_replayed = 0;
};

}  // namespace curvefem::meshing::editing
