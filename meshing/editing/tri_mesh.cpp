#include "meshing/editing/tri_mesh.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::editing {

int TriMesh::local_vertex(Id f, Id v) const {
  const Cell& c = cell(f);
  for (int i = 0; i < 3; ++i)
    if (c[i] == v) return i;
  return -1;
}

int TriMesh::local_edge_of(Id f, Id a, Id b) const {
  const int la = local_vertex(f, a), lb = local_vertex(f, b);
  CF_ASSERT(la >= 0 && lb >= 0 && la != lb, "edge not in face");
  return 3 - la - lb;
}

TriMesh::Tuple TriMesh::tuple(Id f, int lv, int le) const {
  CF_ASSERT(lv != le, "tuple: the vertex must lie on the edge");
  return Tuple{cell(f)[lv], static_cast<std::int8_t>(le), f, cell_hash(f)};
}

std::optional<TriMesh::Tuple> TriMesh::edge_tuple(Id a, Id b) const {
  const Id e[2] = {a, b};
  auto faces = cells_containing(std::span<const Id>(e, 2));
  if (faces.empty()) return std::nullopt;
  const Id f = faces.front();
  return tuple(f, local_vertex(f, a), local_edge_of(f, a, b));
}

bool TriMesh::is_valid(const Tuple& t) const {
  if (t.fid == k_no_id || t.fid >= cell_capacity()) return false;
  return !is_cell_removed(t.fid) && cell_hash(t.fid) == t.hash;
}

TriMesh::Tuple TriMesh::switch_vertex(const Tuple& t) const {
  const int lv = local_vertex(t.fid, t.vid);
  const int other = 3 - lv - t.local_edge;
  return Tuple{cell(t.fid)[other], t.local_edge, t.fid, t.hash};
}

TriMesh::Tuple TriMesh::switch_edge(const Tuple& t) const {
  const int lv = local_vertex(t.fid, t.vid);
  return Tuple{t.vid, static_cast<std::int8_t>(3 - lv - t.local_edge), t.fid, t.hash};
}

std::optional<TriMesh::Tuple> TriMesh::switch_face(const Tuple& t) const {
  const Id b = other_vertex(t);
  const Id e[2] = {t.vid, b};
  for (Id f : cells_containing(std::span<const Id>(e, 2))) {
    if (f == t.fid) continue;
    return Tuple{t.vid, static_cast<std::int8_t>(local_edge_of(f, t.vid, b)), f, cell_hash(f)};
  }
  return std::nullopt;
}

bool TriMesh::is_boundary_edge(const Tuple& t) const {
  const Id e[2] = {t.vid, other_vertex(t)};
  return cells_containing(std::span<const Id>(e, 2)).size() == 1;
}

bool TriMesh::is_boundary_vertex(Id v) const {
  for (Id u : one_ring(v)) {
    const Id e[2] = {v, u};
    if (cells_containing(std::span<const Id>(e, 2)).size() == 1) return true;
  }
  return false;
}

std::vector<TriMesh::Tuple> TriMesh::get_edges() const {
  // Each edge is reported by the smallest face containing it; faces are scanned in parallel
  // blocks and the blocks concatenated in order, so the result is the same as a serial scan.
  const std::size_t n = cell_capacity();
  const std::size_t block = 8192, blocks = (n + block - 1) / block;
  std::vector<std::vector<Tuple>> parts(blocks);
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    for (std::size_t f = b * block; f < std::min(n, (b + 1) * block); ++f) {
      if (is_cell_removed(Id(f))) continue;
      const Cell& c = cell(Id(f));
      for (int le = 0; le < 3; ++le) {
        const Id a = c[(le + 1) % 3], bb = c[(le + 2) % 3];
        // The smallest face containing (a, bb): scan the shorter incident list.
        const auto& la = vertex_cells(a);
        const auto& lb = vertex_cells(bb);
        const auto& shorter = la.size() < lb.size() ? la : lb;
        const Id other = la.size() < lb.size() ? bb : a;
        Id smallest = k_no_id;
        for (Id g : shorter) {
          const Cell& gc = cell(g);
          if (gc[0] == other || gc[1] == other || gc[2] == other) {
            smallest = g;
            break;  // incident lists are sorted
          }
        }
        if (smallest == Id(f)) parts[b].push_back(tuple(Id(f), (le + 1) % 3, le));
      }
    }
  });
  std::vector<Tuple> out;
  for (auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

std::vector<TriMesh::Tuple> TriMesh::get_vertices() const {
  std::vector<Tuple> out;
  for (std::size_t v = 0; v < vertex_capacity(); ++v) {
    if (is_vertex_removed(Id(v))) continue;
    const Id f = vertex_cells(Id(v)).front();
    const int lv = local_vertex(f, Id(v));
    out.push_back(tuple(f, lv, (lv + 1) % 3));
  }
  return out;
}

std::vector<TriMesh::Tuple> TriMesh::get_faces() const {
  std::vector<Tuple> out;
  for (std::size_t f = 0; f < cell_capacity(); ++f)
    if (!is_cell_removed(Id(f))) out.push_back(tuple(Id(f), 0, 2));
  return out;
}

std::vector<TriMesh::Tuple> TriMesh::edges_of_faces(const std::vector<Id>& faces) const {
  std::vector<std::pair<Id, Id>> seen;
  std::vector<Tuple> out;
  for (Id f : faces) {
    if (is_cell_removed(f)) continue;
    const Cell& c = cell(f);
    for (int le = 0; le < 3; ++le) {
      Id a = c[(le + 1) % 3], b = c[(le + 2) % 3];
      std::pair<Id, Id> key = std::minmax(a, b);
      if (std::find(seen.begin(), seen.end(), key) != seen.end()) continue;
      seen.push_back(key);
      out.push_back(tuple(f, (le + 1) % 3, le));
    }
  }
  return out;
}

std::vector<TriMesh::Tuple> TriMesh::vertex_edges(Id v) const {
  std::vector<Tuple> out;
  std::vector<Id> seen;
  for (Id f : vertex_cells(v)) {
    const int lv = local_vertex(f, v);
    for (int le = 0; le < 3; ++le) {
      if (le == lv) continue;
      const Id other = cell(f)[3 - lv - le];
      if (std::find(seen.begin(), seen.end(), other) != seen.end()) continue;
      seen.push_back(other);
      out.push_back(tuple(f, lv, le));
    }
  }
  return out;
}

const OperationRecord& TriMesh::operation_record() const {
  return m_records[current_thread_slot()];
}

std::optional<TriMesh::Tuple> TriMesh::finish(OperationRecord& rec, bool after_ok,
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

std::optional<TriMesh::Tuple> TriMesh::split_edge(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!split_edge_before(t)) return reject(Rejection::before), std::nullopt;
  const Id a = t.vid, b = other_vertex(t);
  const Id e[2] = {a, b};
  const std::vector<Id> faces = cells_containing(std::span<const Id>(e, 2));
  begin_operation();
  const Id m = allocate_vertex();
  Replacement r;
  r.old_cells = faces;
  for (Id f : faces) {
    r.new_cells.push_back({replaced(cell(f), b, m), f});
    r.new_cells.push_back({replaced(cell(f), a, m), f});
  }
  r.split_vertex = m;
  r.split_a = a;
  r.split_b = b;
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{
      .v0 = a, .v1 = b, .new_vertex = m, .old_cells = faces, .new_cells = replace(r)};
  const Id f0 = rec.new_cells.front();
  const Tuple result = tuple(f0, local_vertex(f0, m), local_edge_of(f0, m, a));
  rec.affected_cells = rec.new_cells;
  return finish(rec, split_edge_after(rec), result);
}

std::optional<TriMesh::Tuple> TriMesh::collapse_edge(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!collapse_edge_before(t)) return reject(Rejection::before), std::nullopt;
  const Id a = t.vid, b = other_vertex(t);
  if (!link_condition(a, b)) return reject(Rejection::topology), std::nullopt;
  const std::vector<Id> star = vertex_cells(a);
  begin_operation();
  Replacement r;
  r.old_cells = star;
  for (Id f : star)
    if (local_vertex(f, b) < 0) r.new_cells.push_back({replaced(cell(f), a, b), f});
  r.collapse_from = a;
  r.collapse_to = b;
  if (r.new_cells.empty()) {
    rollback_operation(Rejection::topology);
    return std::nullopt;
  }
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{.v0 = a, .v1 = b, .old_cells = star, .new_cells = replace(r)};
  rec.affected_cells = vertex_cells(b);
  const Id f0 = rec.new_cells.front();
  const int lb = local_vertex(f0, b);
  const Tuple result = tuple(f0, lb, (lb + 1) % 3);
  return finish(rec, collapse_edge_after(rec), result);
}

std::optional<TriMesh::Tuple> TriMesh::swap_edge(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!swap_edge_before(t)) return reject(Rejection::before), std::nullopt;
  const Id a = t.vid, b = other_vertex(t);
  const Id e[2] = {a, b};
  const std::vector<Id> faces = cells_containing(std::span<const Id>(e, 2));
  if (faces.size() != 2) return reject(Rejection::topology), std::nullopt;
  auto third = [&](Id f) {
    for (Id v : cell(f))
      if (v != a && v != b) return v;
    return k_no_id;
  };
  const Id f1 = faces[0], c = third(faces[0]), d = third(faces[1]);
  const Id cd[2] = {c, d};
  if (c == d || !cells_containing(std::span<const Id>(cd, 2)).empty())
    return reject(Rejection::topology), std::nullopt;
  begin_operation();
  Replacement r;
  r.old_cells = faces;
  // Each new face keeps a cavity-boundary edge of f1, so substituting in f1 keeps orientation.
  r.new_cells.push_back({replaced(cell(f1), b, d), f1});
  r.new_cells.push_back({replaced(cell(f1), a, d), faces[1]});
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{
      .v0 = a, .v1 = b, .new_edge = {c, d}, .old_cells = faces, .new_cells = replace(r)};
  const Id g = rec.new_cells.front();
  const Tuple result = tuple(g, local_vertex(g, c), local_edge_of(g, c, d));
  rec.affected_cells = rec.new_cells;
  return finish(rec, swap_edge_after(rec), result);
}

std::optional<TriMesh::Tuple> TriMesh::smooth_vertex(const Tuple& t) {
  if (!is_valid(t)) return reject(Rejection::invalid_tuple), std::nullopt;
  if (!smooth_before(t)) return reject(Rejection::before), std::nullopt;
  begin_operation();
  OperationRecord& rec = m_records[current_thread_slot()];
  rec = OperationRecord{.v0 = t.vid, .new_cells = vertex_cells(t.vid)};
  rec.affected_cells = rec.new_cells;
  return finish(rec, smooth_after(rec), t);
}

}  // namespace curvefem::meshing::editing
