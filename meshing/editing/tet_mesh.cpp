#include "meshing/editing/tet_mesh.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::editing {

namespace {
constexpr int k_edges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
constexpr int k_faces[4][3] = {{0, 1, 2}, {0, 2, 3}, {0, 1, 3}, {1, 2, 3}};

int edge_index(int i, int j) {
  for (int e = 0; e < 6; ++e)
    if ((k_edges[e][0] == i && k_edges[e][1] == j) || (k_edges[e][0] == j && k_edges[e][1] == i))
      return e;
  return -1;
}
bool face_has(int f, int i) {
  return k_faces[f][0] == i || k_faces[f][1] == i || k_faces[f][2] == i;
}
// The candidates whose key appears first, in candidate order (the order a linear scan of the
// keys seen so far gives, which the schedulers' seeding depends on). Small lists (the cavity of
// one operation) are scanned; large ones (a whole mesh) are sorted, so this is O(n log n).
template <class Tuple, class Key>
std::vector<Tuple> first_of_each_key(const std::vector<Key>& keys,
                                     const std::vector<Tuple>& candidates) {
  std::vector<Tuple> out;
  if (keys.size() <= 64) {
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (std::find(keys.begin(), keys.begin() + std::ptrdiff_t(i), keys[i]) ==
          keys.begin() + std::ptrdiff_t(i))
        out.push_back(candidates[i]);
    return out;
  }
  std::vector<std::uint32_t> order(keys.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = std::uint32_t(i);
  std::sort(order.begin(), order.end(), [&keys](std::uint32_t a, std::uint32_t b) {
    return keys[a] < keys[b] || (keys[a] == keys[b] && a < b);
  });
  std::vector<char> first(keys.size(), 0);
  for (std::size_t r = 0; r < order.size(); ++r)
    if (r == 0 || keys[order[r]] != keys[order[r - 1]]) first[order[r]] = 1;
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (first[i]) out.push_back(candidates[i]);
  return out;
}

int face_index(int i, int j, int k) {
  for (int f = 0; f < 4; ++f)
    if (face_has(f, i) && face_has(f, j) && face_has(f, k)) return f;
  return -1;
}
}  // namespace

int TetMesh::local_vertex(Id t, Id v) const {
  const Cell& c = cell(t);
  for (int i = 0; i < 4; ++i)
    if (c[i] == v) return i;
  return -1;
}

TetMesh::Tuple TetMesh::tuple(Id t, int lv, int le, int lf) const {
  return Tuple{cell(t)[lv], static_cast<std::int8_t>(le), static_cast<std::int8_t>(lf), t,
               cell_hash(t)};
}

TetMesh::Tuple TetMesh::tuple_on(Id t, Id a, Id b, Id c) const {
  const int la = local_vertex(t, a), lb = local_vertex(t, b), lc = local_vertex(t, c);
  CF_ASSERT(la >= 0 && lb >= 0 && lc >= 0, "tuple_on: vertex not in tet");
  return tuple(t, la, edge_index(la, lb), face_index(la, lb, lc));
}

std::optional<TetMesh::Tuple> TetMesh::edge_tuple(Id a, Id b) const {
  const Id e[2] = {a, b};
  auto tets = cells_containing(std::span<const Id>(e, 2));
  if (tets.empty()) return std::nullopt;
  const Id t = tets.front();
  Id c = k_no_id;
  for (Id v : cell(t))
    if (v != a && v != b) c = v;
  return tuple_on(t, a, b, c);
}

std::optional<TetMesh::Tuple> TetMesh::face_tuple(Id a, Id b, Id c) const {
  const Id f[3] = {a, b, c};
  auto tets = cells_containing(std::span<const Id>(f, 3));
  if (tets.empty()) return std::nullopt;
  return tuple_on(tets.front(), a, b, c);
}

bool TetMesh::is_valid(const Tuple& t) const {
  if (t.tid == k_no_id || t.tid >= cell_capacity()) return false;
  return !is_cell_removed(t.tid) && cell_hash(t.tid) == t.hash;
}

TetMesh::Tuple TetMesh::switch_vertex(const Tuple& t) const {
  const int lv = local_vertex(t.tid, t.vid);
  const int other =
      k_edges[t.local_edge][0] == lv ? k_edges[t.local_edge][1] : k_edges[t.local_edge][0];
  Tuple r = t;
  r.vid = cell(t.tid)[other];
  return r;
}

TetMesh::Tuple TetMesh::switch_edge(const Tuple& t) const {
  const int lv = local_vertex(t.tid, t.vid);
  const int other_on_edge =
      k_edges[t.local_edge][0] == lv ? k_edges[t.local_edge][1] : k_edges[t.local_edge][0];
  int third = -1;
  for (int i : k_faces[t.local_face])
    if (i != lv && i != other_on_edge) third = i;
  Tuple r = t;
  r.local_edge = static_cast<std::int8_t>(edge_index(lv, third));
  return r;
}

TetMesh::Tuple TetMesh::switch_face(const Tuple& t) const {
  const int i = k_edges[t.local_edge][0], j = k_edges[t.local_edge][1];
  Tuple r = t;
  for (int f = 0; f < 4; ++f)
    if (f != t.local_face && face_has(f, i) && face_has(f, j))
      r.local_face = static_cast<std::int8_t>(f);
  return r;
}

std::array<Id, 3> TetMesh::face_vertices(const Tuple& t) const {
  const Cell& c = cell(t.tid);
  return {c[k_faces[t.local_face][0]], c[k_faces[t.local_face][1]], c[k_faces[t.local_face][2]]};
}

std::optional<TetMesh::Tuple> TetMesh::switch_tetrahedron(const Tuple& t) const {
  const auto f = face_vertices(t);
  const Id b = other_vertex(t);
  Id c = k_no_id;
  for (Id v : f)
    if (v != t.vid && v != b) c = v;
  for (Id o : cells_containing(std::span<const Id>(f.data(), 3)))
    if (o != t.tid) return tuple_on(o, t.vid, b, c);
  return std::nullopt;
}

bool TetMesh::is_boundary_face(const Tuple& t) const {
  const auto f = face_vertices(t);
  return cells_containing(std::span<const Id>(f.data(), 3)).size() == 1;
}

bool TetMesh::is_boundary_edge(const Tuple& t) const {
  const Id a = t.vid, b = other_vertex(t);
  const Id e[2] = {a, b};
  const auto tets = cells_containing(std::span<const Id>(e, 2));
  return edge_ring(a, b, tets).empty();
}

std::vector<TetMesh::Tuple> TetMesh::get_edges() const {
  std::vector<Tuple> out;
  for (std::size_t t = 0; t < cell_capacity(); ++t) {
    if (is_cell_removed(Id(t))) continue;
    const Cell& c = cell(Id(t));
    for (int e = 0; e < 6; ++e) {
      const Id ev[2] = {c[k_edges[e][0]], c[k_edges[e][1]]};
      if (cells_containing(std::span<const Id>(ev, 2)).front() != Id(t)) continue;
      int lf = 0;
      while (!(face_has(lf, k_edges[e][0]) && face_has(lf, k_edges[e][1]))) ++lf;
      out.push_back(tuple(Id(t), k_edges[e][0], e, lf));
    }
  }
  return out;
}

std::vector<TetMesh::Tuple> TetMesh::get_faces() const {
  std::vector<Tuple> out;
  for (std::size_t t = 0; t < cell_capacity(); ++t) {
    if (is_cell_removed(Id(t))) continue;
    const Cell& c = cell(Id(t));
    for (int f = 0; f < 4; ++f) {
      const Id fv[3] = {c[k_faces[f][0]], c[k_faces[f][1]], c[k_faces[f][2]]};
      if (cells_containing(std::span<const Id>(fv, 3)).front() != Id(t)) continue;
      out.push_back(tuple(Id(t), k_faces[f][0], edge_index(k_faces[f][0], k_faces[f][1]), f));
    }
  }
  return out;
}

std::vector<TetMesh::Tuple> TetMesh::get_vertices() const {
  std::vector<Tuple> out;
  for (std::size_t v = 0; v < vertex_capacity(); ++v) {
    if (is_vertex_removed(Id(v))) continue;
    const Id t = vertex_cells(Id(v)).front();
    const int lv = local_vertex(t, Id(v));
    const int lo = (lv + 1) % 4, lt = (lv + 2) % 4;
    out.push_back(tuple(t, lv, edge_index(lv, lo), face_index(lv, lo, lt)));
  }
  return out;
}

std::vector<TetMesh::Tuple> TetMesh::get_tets() const {
  std::vector<Tuple> out;
  for (std::size_t t = 0; t < cell_capacity(); ++t)
    if (!is_cell_removed(Id(t))) out.push_back(tuple(Id(t), 0, 0, 0));
  return out;
}

std::vector<TetMesh::Tuple> TetMesh::edges_of_tets(const std::vector<Id>& tets) const {
  std::vector<std::array<Id, 3>> keys;
  std::vector<Tuple> candidates;
  for (Id t : tets) {
    if (is_cell_removed(t)) continue;
    const Cell& c = cell(t);
    for (int e = 0; e < 6; ++e) {
      const auto [a, b] = std::minmax(c[k_edges[e][0]], c[k_edges[e][1]]);
      keys.push_back({a, b, k_no_id});
      int lf = 0;
      while (!(face_has(lf, k_edges[e][0]) && face_has(lf, k_edges[e][1]))) ++lf;
      candidates.push_back(tuple(t, k_edges[e][0], e, lf));
    }
  }
  return first_of_each_key(keys, candidates);
}

std::vector<TetMesh::Tuple> TetMesh::faces_of_tets(const std::vector<Id>& tets) const {
  std::vector<std::array<Id, 3>> keys;
  std::vector<Tuple> candidates;
  for (Id t : tets) {
    if (is_cell_removed(t)) continue;
    const Cell& c = cell(t);
    for (int f = 0; f < 4; ++f) {
      std::array<Id, 3> key{c[k_faces[f][0]], c[k_faces[f][1]], c[k_faces[f][2]]};
      std::sort(key.begin(), key.end());
      keys.push_back(key);
      candidates.push_back(tuple(t, k_faces[f][0], edge_index(k_faces[f][0], k_faces[f][1]), f));
    }
  }
  return first_of_each_key(keys, candidates);
}

std::vector<Id> TetMesh::edge_ring(Id a, Id b, const std::vector<Id>& tets) const {
  std::vector<std::pair<Id, Id>> pairs;
  for (Id t : tets) {
    std::pair<Id, Id> p{k_no_id, k_no_id};
    for (Id v : cell(t)) {
      if (v == a || v == b) continue;
      (p.first == k_no_id ? p.first : p.second) = v;
    }
    pairs.push_back(p);
  }
  if (pairs.size() < 3) return {};
  std::vector<Id> ring{pairs[0].first, pairs[0].second};
  std::vector<bool> used(pairs.size(), false);
  used[0] = true;
  for (std::size_t step = 1; step < pairs.size(); ++step) {
    const Id last = ring.back();
    bool found = false;
    for (std::size_t i = 0; i < pairs.size() && !found; ++i) {
      if (used[i]) continue;
      if (pairs[i].first == last || pairs[i].second == last) {
        used[i] = true;
        found = true;
        ring.push_back(pairs[i].first == last ? pairs[i].second : pairs[i].first);
      }
    }
    if (!found) return {};
  }
  if (ring.back() != ring.front()) return {};  // open fan: a boundary edge
  ring.pop_back();
  return ring;
}

const OperationRecord& TetMesh::operation_record() const {
  return m_records[current_thread_slot()];
}

std::optional<TetMesh::Tuple> TetMesh::finish(OperationRecord& rec, bool after_ok,
                                              const Tuple& result) {
  if (!after_ok) {
    rollback_operation(Rejection::after);
    return std::nullopt;
  }
  if (!invariants(rec)) {
    rollback_operation(Rejection::invariant);
    return std::nullopt;
  }
  commit_operation();
  return result;
}

std::optional<TetMesh::Tuple> TetMesh::split_edge(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!split_edge_before(t)) return reject(Rejection::before), std::nullopt;
  const Id a = t.vid, b = other_vertex(t);
  const Id e[2] = {a, b};
  const std::vector<Id> tets = cells_containing(std::span<const Id>(e, 2));
  begin_operation();
  const Id m = allocate_vertex();
  Replacement r;
  r.old_cells = tets;
  for (Id s : tets) {
    r.new_cells.push_back({replaced(cell(s), b, m), s});
    r.new_cells.push_back({replaced(cell(s), a, m), s});
  }
  r.split_vertex = m;
  r.split_a = a;
  r.split_b = b;
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{
      .v0 = a, .v1 = b, .new_vertex = m, .old_cells = tets, .new_cells = replace(r)};
  const Id t0 = rec.new_cells.front();
  Id c = k_no_id;
  for (Id v : cell(t0))
    if (v != a && v != m) c = v;
  rec.affected_cells = rec.new_cells;
  return finish(rec, split_edge_after(rec), tuple_on(t0, m, a, c));
}

std::optional<TetMesh::Tuple> TetMesh::collapse_edge(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!collapse_edge_before(t)) return reject(Rejection::before), std::nullopt;
  const Id a = t.vid, b = other_vertex(t);
  if (!link_condition(a, b)) return reject(Rejection::topology), std::nullopt;
  const std::vector<Id> star = vertex_cells(a);
  Replacement r;
  r.old_cells = star;
  for (Id s : star)
    if (local_vertex(s, b) < 0) r.new_cells.push_back({replaced(cell(s), a, b), s});
  if (r.new_cells.empty()) return reject(Rejection::topology), std::nullopt;
  r.collapse_from = a;
  r.collapse_to = b;
  begin_operation();
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{.v0 = a, .v1 = b, .old_cells = star, .new_cells = replace(r)};
  rec.affected_cells = vertex_cells(b);
  const Id t0 = rec.new_cells.front();
  const int lb = local_vertex(t0, b);
  const int lo = (lb + 1) % 4, lt = (lb + 2) % 4;
  return finish(rec, collapse_edge_after(rec),
                tuple(t0, lb, edge_index(lb, lo), face_index(lb, lo, lt)));
}

std::optional<TetMesh::Tuple> TetMesh::swap_face_23(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!swap_face_before(t)) return reject(Rejection::before), std::nullopt;
  const auto f = face_vertices(t);
  const std::vector<Id> tets = cells_containing(std::span<const Id>(f.data(), 3));
  if (tets.size() != 2) return reject(Rejection::topology), std::nullopt;
  auto apex = [&](Id s) {
    for (Id v : cell(s))
      if (v != f[0] && v != f[1] && v != f[2]) return v;
    return k_no_id;
  };
  const Id t1 = tets[0], d = apex(tets[0]), e = apex(tets[1]);
  const Id de[2] = {d, e};
  if (!cells_containing(std::span<const Id>(de, 2)).empty())
    return reject(Rejection::topology), std::nullopt;
  Replacement r;
  r.old_cells = tets;
  for (Id v : f) r.new_cells.push_back({replaced(cell(t1), v, e), t1});
  begin_operation();
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{
      .v0 = f[0], .v1 = f[1], .new_edge = {d, e}, .old_cells = tets, .new_cells = replace(r)};
  const Id t0 = rec.new_cells.front();
  Id c = k_no_id;
  for (Id v : cell(t0))
    if (v != d && v != e) c = v;
  rec.affected_cells = rec.new_cells;
  return finish(rec, swap_face_after(rec), tuple_on(t0, d, e, c));
}

std::optional<TetMesh::Tuple> TetMesh::swap_edge_32(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!swap_edge_before(t)) return reject(Rejection::before), std::nullopt;
  const Id a = t.vid, b = other_vertex(t);
  const Id e[2] = {a, b};
  const std::vector<Id> tets = cells_containing(std::span<const Id>(e, 2));
  if (tets.size() != 3) return reject(Rejection::topology), std::nullopt;
  const std::vector<Id> ring = edge_ring(a, b, tets);
  if (ring.size() != 3) return reject(Rejection::topology), std::nullopt;
  if (!cells_containing(std::span<const Id>(ring.data(), 3)).empty())
    return reject(Rejection::topology), std::nullopt;
  const Id t0 = tets[0];
  Id z = k_no_id;
  for (Id v : ring)
    if (local_vertex(t0, v) < 0) z = v;
  Replacement r;
  r.old_cells = tets;
  r.new_cells.push_back({replaced(cell(t0), b, z), t0});
  r.new_cells.push_back({replaced(cell(t0), a, z), t0});
  begin_operation();
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{.v0 = a, .v1 = b, .old_cells = tets, .new_cells = replace(r)};
  rec.affected_cells = rec.new_cells;
  return finish(rec, swap_edge_after(rec),
                tuple_on(rec.new_cells.front(), ring[0], ring[1], ring[2]));
}

std::optional<TetMesh::Tuple> TetMesh::swap_edge_44(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!swap_edge_before(t)) return reject(Rejection::before), std::nullopt;
  const Id a = t.vid, b = other_vertex(t);
  const Id e[2] = {a, b};
  const std::vector<Id> tets = cells_containing(std::span<const Id>(e, 2));
  if (tets.size() != 4) return reject(Rejection::topology), std::nullopt;
  std::vector<Id> ring = edge_ring(a, b, tets);
  if (ring.size() != 4) return reject(Rejection::topology), std::nullopt;
  Id c0 = k_no_id;
  for (Id v : face_vertices(t))
    if (v != a && v != b) c0 = v;
  std::rotate(ring.begin(), std::find(ring.begin(), ring.end(), c0), ring.end());
  const Id diag[2] = {ring[0], ring[2]};
  if (!cells_containing(std::span<const Id>(diag, 2)).empty())
    return reject(Rejection::topology), std::nullopt;
  auto tet_with = [&](Id x, Id y) {
    for (Id s : tets)
      if (local_vertex(s, x) >= 0 && local_vertex(s, y) >= 0) return s;
    return k_no_id;
  };
  const Id t01 = tet_with(ring[0], ring[1]), t23 = tet_with(ring[2], ring[3]);
  Replacement r;
  r.old_cells = tets;
  r.new_cells.push_back({replaced(cell(t01), b, ring[2]), t01});
  r.new_cells.push_back({replaced(cell(t01), a, ring[2]), t01});
  r.new_cells.push_back({replaced(cell(t23), b, ring[0]), t23});
  r.new_cells.push_back({replaced(cell(t23), a, ring[0]), t23});
  begin_operation();
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{
      .v0 = a, .v1 = b, .new_edge = {ring[0], ring[2]}, .old_cells = tets, .new_cells = replace(r)};
  rec.affected_cells = rec.new_cells;
  return finish(rec, swap_edge_after(rec), tuple_on(rec.new_cells.front(), ring[0], ring[2], a));
}

std::optional<TetMesh::Tuple> TetMesh::smooth_vertex(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!smooth_before(t)) return reject(Rejection::before), std::nullopt;
  begin_operation();
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{.v0 = t.vid, .new_cells = vertex_cells(t.vid)};
  rec.affected_cells = rec.new_cells;
  return finish(rec, smooth_after(rec), t);
}

}  // namespace curvefem::meshing::editing
