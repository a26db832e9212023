#include "meshing/editing/simplex_mesh.hpp"

#include <algorithm>
#include <map>
#include <sstream>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::editing {

namespace {

thread_local int t_slot = 0;

// Local sub-simplices: triangle edge i is opposite vertex i; tetrahedron edges
// {01,12,02,03,13,23}, faces {012,023,013,123} (the tuple conventions).
constexpr int k_tri_edges[3][2] = {{1, 2}, {0, 2}, {0, 1}};
constexpr int k_tet_edges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
constexpr int k_tet_faces[4][3] = {{0, 1, 2}, {0, 2, 3}, {0, 1, 3}, {1, 2, 3}};

constexpr Id k_infinity = k_no_id - 1;  // the virtual vertex closing the boundary

using Key = std::array<Id, 3>;

// All non-empty subsets of verts (size <= 3) as keys.
void add_subsets(std::vector<Key>& out, const Id* verts, int n) {
  for (int mask = 1; mask < (1 << n); ++mask) {
    Key k{k_no_id, k_no_id, k_no_id};
    int m = 0;
    for (int i = 0; i < n; ++i)
      if (mask & (1 << i)) k[m++] = verts[i];
    std::sort(k.begin(), k.begin() + m);
    out.push_back(k);
  }
}

void sort_unique(std::vector<Key>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

void insert_sorted(std::vector<Id>& list, Id x) {
  list.insert(std::lower_bound(list.begin(), list.end(), x), x);
}
void erase_sorted(std::vector<Id>& list, Id x) {
  auto it = std::lower_bound(list.begin(), list.end(), x);
  if (it != list.end() && *it == x) list.erase(it);
}

// Sign of the permutation sorting `ids` (distinct).
template <std::size_t M>
int permutation_sign(std::array<Id, M> ids) {
  int sign = 1;
  for (std::size_t i = 0; i < M; ++i)
    for (std::size_t j = i + 1; j < M; ++j)
      if (ids[j] < ids[i]) sign = -sign;
  return sign;
}

}  // namespace

int current_thread_slot() { return t_slot; }
ThreadSlotScope::ThreadSlotScope(int slot) : m_previous(t_slot) {
  CF_VERIFY(slot >= 0 && slot < k_max_threads, "thread slot out of range");
  t_slot = slot;
}
ThreadSlotScope::~ThreadSlotScope() { t_slot = m_previous; }

AttributeBase::AttributeBase(SimplexMeshBase& mesh, int dim) : m_mesh(&mesh), m_dim(dim) {
  mesh.m_attributes.push_back(this);
}
AttributeBase::~AttributeBase() {
  auto& list = m_mesh->m_attributes;
  list.erase(std::remove(list.begin(), list.end(), this), list.end());
}
bool AttributeBase::journaling() const { return m_mesh->operation_active(); }
std::size_t AttributeBase::initial_slot_count() const {
  return m_mesh->attribute_slot_count(m_dim);
}

template <int N>
SimplexMesh<N>::SimplexMesh() = default;
template <int N>
SimplexMesh<N>::~SimplexMesh() = default;

template <int N>
int SimplexMesh<N>::slots_per_cell(int dim) {
  if (dim == N - 1) return 1;
  if (N == 3) return 3;     // triangle edges
  return dim == 1 ? 6 : 4;  // tetrahedron edges, faces
}

template <int N>
std::size_t SimplexMesh<N>::slot(Id c, int local, int dim) {
  return std::size_t(c) * slots_per_cell(dim) + local;
}

template <int N>
std::span<const int> SimplexMesh<N>::local_simplex(int dim, int local) {
  if (N == 3) return {k_tri_edges[local], 2};
  if (dim == 1) return {k_tet_edges[local], 2};
  return {k_tet_faces[local], 3};
}

template <int N>
std::size_t SimplexMesh<N>::attribute_slot_count(int dim) const {
  CF_VERIFY(dim >= 0 && dim <= N - 1, "attribute dimension out of range");
  if (dim == 0) return vertex_capacity();
  return cell_capacity() * slots_per_cell(dim);
}

template <int N>
bool SimplexMesh<N>::operation_active() const {
  return m_undo[current_thread_slot()].active;
}

template <int N>
Rejection SimplexMesh<N>::last_rejection() const {
  return m_undo[current_thread_slot()].last;
}

template <int N>
void SimplexMesh<N>::grow_cell_attributes(std::size_t capacity) {
  for (AttributeBase* a : m_attributes)
    if (a->dimension() > 0) a->grow_to(capacity * slots_per_cell(a->dimension()));
}

template <int N>
void SimplexMesh<N>::initialize(std::size_t num_vertices, const std::vector<Cell>& cells) {
  m_vertices.reset(num_vertices);
  m_locks.reset(num_vertices);
  m_cells.reset(cells.size());
  for (std::size_t c = 0; c < cells.size(); ++c) {
    for (Id v : cells[c]) {
      if (v >= num_vertices) {
        throw InputError("cell " + std::to_string(c) + " references vertex " + std::to_string(v) +
                             " but the mesh has " + std::to_string(num_vertices) + " vertices",
                         ErrorContext{.face = static_cast<std::int64_t>(c)});
      }
    }
    m_cells[c].v = cells[c];
    m_cells[c].state.store(0);
    for (Id v : cells[c]) m_vertices[v].cells.push_back(Id(c));
  }
  std::int64_t live = 0;
  for (std::size_t v = 0; v < num_vertices; ++v) {
    m_vertices[v].removed = m_vertices[v].cells.empty();
    live += m_vertices[v].removed ? 0 : 1;
  }
  m_live_vertices = live;
  m_live_cells = static_cast<std::int64_t>(cells.size());
  for (AttributeBase* a : m_attributes) a->grow_to(attribute_slot_count(a->dimension()));
  for (auto& log : m_undo) log = UndoLog{};
}

template <int N>
std::vector<Id> SimplexMesh<N>::live_vertices() const {
  std::vector<Id> out;
  for (std::size_t v = 0; v < vertex_capacity(); ++v)
    if (!is_vertex_removed(Id(v))) out.push_back(Id(v));
  return out;
}

template <int N>
std::vector<Id> SimplexMesh<N>::live_cells() const {
  std::vector<Id> out;
  for (std::size_t c = 0; c < cell_capacity(); ++c)
    if (!is_cell_removed(Id(c))) out.push_back(Id(c));
  return out;
}

template <int N>
std::vector<Id> SimplexMesh<N>::one_ring(Id v) const {
  std::vector<Id> out;
  for (Id c : vertex_cells(v))
    for (Id u : cell(c))
      if (u != v) out.push_back(u);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

template <int N>
std::vector<Id> SimplexMesh<N>::cells_containing(std::span<const Id> verts) const {
  std::vector<Id> out;
  if (verts.empty()) return out;
  // Scan the shortest incident list and test membership of the other vertices.
  std::size_t best = 0;
  for (std::size_t i = 1; i < verts.size(); ++i)
    if (vertex_cells(verts[i]).size() < vertex_cells(verts[best]).size()) best = i;
  for (Id c : vertex_cells(verts[best])) {
    const Cell& cv = cell(c);
    bool all = true;
    for (Id u : verts) all = all && std::find(cv.begin(), cv.end(), u) != cv.end();
    if (all) out.push_back(c);
  }
  return out;
}

template <int N>
bool SimplexMesh<N>::is_boundary_facet(std::span<const Id> facet) const {
  return cells_containing(facet).size() == 1;
}

template <int N>
int SimplexMesh<N>::local_index_of(Id c, std::span<const Id> verts) const {
  const Cell& cv = cell(c);
  const int dim = int(verts.size()) - 1;
  for (int l = 0; l < slots_per_cell(dim); ++l) {
    auto loc = local_simplex(dim, l);
    bool all = true;
    for (int i : loc) all = all && std::find(verts.begin(), verts.end(), cv[i]) != verts.end();
    if (all) return l;
  }
  CF_VERIFY(false, "local_index_of: simplex not in cell");
  return -1;
}

template <int N>
typename SimplexMesh<N>::Cell SimplexMesh<N>::replaced(const Cell& c, Id from, Id to) {
  Cell out = c;
  for (Id& v : out)
    if (v == from) v = to;
  return out;
}

// ---------------------------------------------------------------------------------------------
// Locks

template <int N>
bool SimplexMesh<N>::try_lock_vertex(Id v) {
  const int me = current_thread_slot() + 1;
  int expected = 0;
  if (m_locks[v].owner.compare_exchange_strong(expected, me, std::memory_order_acquire)) {
    m_held_locks[me - 1].push_back(v);
    return true;
  }
  return expected == me;
}

template <int N>
bool SimplexMesh<N>::try_lock_region(std::span<const Id> seeds, int rings) {
  std::vector<Id> frontier(seeds.begin(), seeds.end());
  for (Id v : frontier)
    if (!try_lock_vertex(v)) return false;
  std::vector<Id> next;
  for (int r = 0; r < rings; ++r) {
    next.clear();
    for (Id v : frontier)
      for (Id c : vertex_cells(v))
        for (Id u : cell(c)) next.push_back(u);
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    for (Id u : next)
      if (!try_lock_vertex(u)) return false;
    frontier.swap(next);
  }
  return true;
}

template <int N>
void SimplexMesh<N>::release_vertex_locks() {
  auto& held = m_held_locks[current_thread_slot()];
  for (Id v : held) m_locks[v].owner.store(0, std::memory_order_release);
  held.clear();
}

// ---------------------------------------------------------------------------------------------
// Operations: replacement, commit, rollback

template <int N>
void SimplexMesh<N>::begin_operation() {
  UndoLog& log = m_undo[current_thread_slot()];
  CF_ASSERT(!log.active, "nested operation");
  log.saved_vertices.clear();
  log.old_cells.clear();
  log.new_cells.clear();
  log.new_vertices.clear();
  log.removed_vertices.clear();
  log.active = true;
  log.last = Rejection::none;
}

template <int N>
Id SimplexMesh<N>::allocate_vertex() {
  UndoLog& log = m_undo[current_thread_slot()];
  const Id v = Id(m_vertices.append());
  m_locks.grow_to(std::size_t(v) + 1);
  m_vertices[v].cells.clear();
  m_vertices[v].removed = false;
  for (AttributeBase* a : m_attributes)
    if (a->dimension() == 0) a->grow_to(std::size_t(v) + 1);
  log.new_vertices.push_back(v);
  log.saved_vertices.emplace_back(v, VertexRecord{{}, true});
  m_live_vertices.fetch_add(1);
  // Under a locking scheduler the new vertex belongs to this thread until the locks are released.
  if (!m_held_locks[current_thread_slot()].empty()) try_lock_vertex(v);
  return v;
}

template <int N>
std::vector<Id> SimplexMesh<N>::replace(const Replacement& r) {
  UndoLog& log = m_undo[current_thread_slot()];
  CF_ASSERT(log.active, "replace outside an operation");
  auto save = [&](Id v) {
    for (const auto& [u, rec] : log.saved_vertices)
      if (u == v) return;
    log.saved_vertices.emplace_back(v, m_vertices[v]);
  };
  for (Id c : r.old_cells)
    for (Id v : cell(c)) save(v);
  for (const NewCell& nc : r.new_cells)
    for (Id v : nc.v) save(v);

  for (Id c : r.old_cells) {
    m_cells[c].state.fetch_add(3u, std::memory_order_acq_rel);  // hash + 1, removed
    for (Id v : cell(c)) erase_sorted(m_vertices[v].cells, c);
    log.old_cells.push_back(c);
  }
  std::vector<Id> new_ids;
  new_ids.reserve(r.new_cells.size());
  for (const NewCell& nc : r.new_cells) {
    const Id c = Id(m_cells.append());
    m_cells[c].v = nc.v;
    m_cells[c].state.store(0, std::memory_order_release);
    for (Id v : nc.v) insert_sorted(m_vertices[v].cells, c);
    new_ids.push_back(c);
    log.new_cells.push_back(c);
  }
  grow_cell_attributes(cell_capacity());
  for (Id c : r.old_cells)
    for (Id v : cell(c))
      if (m_vertices[v].cells.empty() && !m_vertices[v].removed) {
        m_vertices[v].removed = true;
        log.removed_vertices.push_back(v);
        m_live_vertices.fetch_sub(1);
      }
  m_live_cells.fetch_add(std::int64_t(r.new_cells.size()) - std::int64_t(r.old_cells.size()));
  inherit_attributes(r, new_ids);
  return new_ids;
}

template <int N>
void SimplexMesh<N>::inherit_attributes(const Replacement& r, const std::vector<Id>& new_ids) {
  for (AttributeBase* a : m_attributes) {
    const int dim = a->dimension();
    if (dim == 0) continue;
    if (dim == N - 1) {
      for (std::size_t i = 0; i < new_ids.size(); ++i)
        a->copy_slot(new_ids[i], r.new_cells[i].parent);
      continue;
    }
    // Old sub-simplices by key, with a flag for keys renamed by the collapse.
    struct Entry {
      Key key;
      std::size_t slot;
      bool renamed;
    };
    std::vector<Entry> old_entries;
    const int count = slots_per_cell(dim);
    const int nv = dim + 1;
    for (Id c : r.old_cells) {
      const Cell& cv = cell(c);
      for (int l = 0; l < count; ++l) {
        auto loc = local_simplex(dim, l);
        Key k{k_no_id, k_no_id, k_no_id};
        bool renamed = false;
        for (int i = 0; i < nv; ++i) {
          Id v = cv[loc[i]];
          if (v == r.collapse_from) {
            v = r.collapse_to;
            renamed = true;
          }
          k[i] = v;
        }
        std::sort(k.begin(), k.begin() + nv);
        old_entries.push_back({k, slot(c, l, dim), renamed});
      }
    }
    // Sources of a key: slots of the simplex itself first, then of the one merged into it.
    auto sources = [&](const Key& k, bool& merged) {
      std::vector<std::size_t> exact, renamed;
      for (const Entry& e : old_entries)
        if (e.key == k) (e.renamed ? renamed : exact).push_back(e.slot);
      merged = !exact.empty() && !renamed.empty();
      exact.insert(exact.end(), renamed.begin(), renamed.end());
      return exact;
    };
    std::vector<Key> merged_keys;
    for (Id c : new_ids) {
      const Cell& cv = cell(c);
      for (int l = 0; l < count; ++l) {
        auto loc = local_simplex(dim, l);
        Key k{k_no_id, k_no_id, k_no_id};
        for (int i = 0; i < nv; ++i) k[i] = cv[loc[i]];
        std::sort(k.begin(), k.begin() + nv);
        bool merged = false;
        std::vector<std::size_t> src = sources(k, merged);
        if (merged) merged_keys.push_back(k);
        if (src.empty() && r.split_vertex != k_no_id &&
            std::find(k.begin(), k.begin() + nv, r.split_vertex) != k.begin() + nv) {
          // A half of a split simplex: the new vertex stands for both split endpoints.
          std::vector<Id> parent;
          for (int i = 0; i < nv; ++i)
            if (k[i] != r.split_vertex) parent.push_back(k[i]);
          parent.push_back(r.split_a);
          parent.push_back(r.split_b);
          std::sort(parent.begin(), parent.end());
          parent.erase(std::unique(parent.begin(), parent.end()), parent.end());
          if (int(parent.size()) == nv) {
            Key pk{k_no_id, k_no_id, k_no_id};
            std::copy(parent.begin(), parent.end(), pk.begin());
            src = sources(pk, merged);
          }
        }
        a->merge_into(slot(c, l, dim), src);
      }
    }
    // Simplices merged by a collapse also live in cells outside the cavity: give every slot
    // the merged value. Keys renamed onto an existing simplex without appearing in a new cell
    // (the face shared with a removed tet) are handled the same way.
    for (const Entry& e : old_entries) {
      if (!e.renamed) continue;
      bool merged = false;
      sources(e.key, merged);
      if (merged) merged_keys.push_back(e.key);
    }
    std::sort(merged_keys.begin(), merged_keys.end());
    merged_keys.erase(std::unique(merged_keys.begin(), merged_keys.end()), merged_keys.end());
    for (const Key& k : merged_keys) {
      bool merged = false;
      const std::vector<std::size_t> src = sources(k, merged);
      const std::span<const Id> verts(k.data(), nv);
      for (Id c : cells_containing(verts))
        a->merge_into(slot(c, local_index_of(c, verts), dim), src);
    }
  }
}

template <int N>
void SimplexMesh<N>::commit_operation() {
  UndoLog& log = m_undo[current_thread_slot()];
  for (AttributeBase* a : m_attributes) a->clear_journal(current_thread_slot());
  log.active = false;
  log.last = Rejection::none;
}

template <int N>
void SimplexMesh<N>::rollback_operation(Rejection why) {
  UndoLog& log = m_undo[current_thread_slot()];
  for (AttributeBase* a : m_attributes) a->rollback(current_thread_slot());
  for (Id c : log.new_cells)
    m_cells[c].state.store(3u, std::memory_order_release);  // dead for good
  for (Id c : log.old_cells) m_cells[c].state.fetch_sub(3u, std::memory_order_acq_rel);
  for (auto& [v, rec] : log.saved_vertices) m_vertices[v] = std::move(rec);
  m_live_cells.fetch_add(std::int64_t(log.old_cells.size()) - std::int64_t(log.new_cells.size()));
  m_live_vertices.fetch_add(std::int64_t(log.removed_vertices.size()) -
                            std::int64_t(log.new_vertices.size()));
  log.active = false;
  log.last = why;
}

template <int N>
void SimplexMesh<N>::reject(Rejection why) {
  m_undo[current_thread_slot()].last = why;
}

// ---------------------------------------------------------------------------------------------
// Link condition: Lk(a) ∩ Lk(b) == Lk(ab), the boundary closed by a virtual vertex.

template <int N>
bool SimplexMesh<N>::link_condition(Id a, Id b) const {
  // A facet through v lies in no cell outside v's star, so counting within the star decides
  // whether it is on the boundary (and is far cheaper than a global lookup). The facets of the
  // star through `v0` (and `v1`) are listed once, sorted: a boundary facet is one used once.
  // The facet of cell cv opposite its corner `skip`, in cell order.
  auto facet = [](const Cell& cv, int skip) {
    std::array<Id, N - 1> f{};
    int k = 0;
    for (int i = 0; i < N; ++i)
      if (i != skip) f[std::size_t(k++)] = cv[i];
    return f;
  };
  auto facet_key = [](const Id* f) {
    Key k{k_no_id, k_no_id, k_no_id};
    std::copy(f, f + (N - 1), k.begin());
    std::sort(k.begin(), k.begin() + (N - 1));
    return k;
  };
  auto boundary_facets = [&](const std::vector<Id>& star, Id v0, Id v1) {
    std::vector<Key> all;
    all.reserve(star.size() * std::size_t(N));
    for (Id c : star) {
      const Cell& cv = cell(c);
      for (int skip = 0; skip < N; ++skip) {
        if (cv[skip] == v0 || cv[skip] == v1) continue;
        const auto f = facet(cv, skip);
        all.push_back(facet_key(f.data()));
      }
    }
    std::sort(all.begin(), all.end());
    std::vector<Key> once;
    for (std::size_t i = 0; i < all.size();) {
      std::size_t j = i + 1;
      while (j < all.size() && all[j] == all[i]) ++j;
      if (j == i + 1) once.push_back(all[i]);
      i = j;
    }
    return once;
  };
  auto facet_is_boundary = [&](const Id* f, const std::vector<Key>& boundary) {
    return std::binary_search(boundary.begin(), boundary.end(), facet_key(f));
  };
  // Every simplex of Lk(a) ∩ Lk(b), and so of Lk(ab), has its vertices among the common
  // neighbours of a and b (and the virtual vertex), so both vertex links are built over those
  // only: the same comparison on far shorter lists.
  std::vector<Id> common;
  {
    const std::vector<Id> na = one_ring(a), nb = one_ring(b);
    std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
  }
  const Id edge[2] = {a, b};
  const std::vector<Id> edge_star = cells_containing(std::span<const Id>(edge, 2));
  {
    // The vertices of Lk(ab) are common neighbours; one more common neighbour is a vertex of
    // Lk(a) ∩ Lk(b) outside Lk(ab), so the condition fails without building the links (the
    // usual way it fails).
    std::vector<Id> around;
    for (Id c : edge_star)
      for (Id u : cell(c))
        if (u != a && u != b) around.push_back(u);
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    if (around != common) return false;
  }
  auto in_common = [&](Id u) { return std::binary_search(common.begin(), common.end(), u); };
  auto vertex_link = [&](Id v) {
    std::vector<Key> link;
    const std::vector<Id>& star = vertex_cells(v);
    const std::vector<Key> boundary = boundary_facets(star, v, k_no_id);
    for (Id c : star) {
      const Cell& cv = cell(c);
      Id rest[N];
      int m = 0;
      for (Id u : cv)
        if (u != v && in_common(u)) rest[m++] = u;
      add_subsets(link, rest, m);
      // Boundary facets of c through v: facet minus v, plus the virtual vertex.
      for (int skip = 0; skip < N; ++skip) {
        if (cv[skip] == v) continue;
        const auto f = facet(cv, skip);
        if (!facet_is_boundary(f.data(), boundary)) continue;
        Id g[N - 1];
        int q = 0;
        for (int i = 0; i < N - 1; ++i)
          if (f[i] != v && in_common(f[i])) g[q++] = f[i];
        g[q++] = k_infinity;
        add_subsets(link, g, q);
      }
    }
    sort_unique(link);
    return link;
  };
  std::vector<Key> la = vertex_link(a), lb = vertex_link(b), lab;
  const std::vector<Key> edge_boundary = boundary_facets(edge_star, a, b);
  for (Id c : edge_star) {
    const Cell& cv = cell(c);
    Id rest[N];
    int m = 0;
    for (Id u : cv)
      if (u != a && u != b) rest[m++] = u;
    add_subsets(lab, rest, m);
    for (int skip = 0; skip < N; ++skip) {
      if (cv[skip] == a || cv[skip] == b) continue;
      const auto f = facet(cv, skip);
      if (!facet_is_boundary(f.data(), edge_boundary)) continue;
      Id g[N - 1];
      int q = 0;
      for (int i = 0; i < N - 1; ++i)
        if (f[i] != a && f[i] != b) g[q++] = f[i];
      g[q++] = k_infinity;
      add_subsets(lab, g, q);
    }
  }
  sort_unique(lab);
  std::vector<Key> both;
  std::set_intersection(la.begin(), la.end(), lb.begin(), lb.end(), std::back_inserter(both));
  return both == lab;
}

// ---------------------------------------------------------------------------------------------
// Consolidation and checks

template <int N>
std::vector<Id> SimplexMesh<N>::consolidate() {
  std::vector<Id> new_of_old_vertex(vertex_capacity(), k_no_id);
  std::vector<std::size_t> vertex_new_to_old;
  for (std::size_t v = 0; v < vertex_capacity(); ++v)
    if (!is_vertex_removed(Id(v))) {
      new_of_old_vertex[v] = Id(vertex_new_to_old.size());
      vertex_new_to_old.push_back(v);
    }
  std::vector<std::size_t> cell_new_to_old;
  std::vector<Cell> cells;
  for (std::size_t c = 0; c < cell_capacity(); ++c) {
    if (is_cell_removed(Id(c))) continue;
    cell_new_to_old.push_back(c);
    Cell cv = cell(Id(c));
    for (Id& v : cv) v = new_of_old_vertex[v];
    cells.push_back(cv);
  }
  for (AttributeBase* a : m_attributes) {
    const int dim = a->dimension();
    if (dim == 0) {
      a->compact(vertex_new_to_old);
    } else {
      const int k = slots_per_cell(dim);
      std::vector<std::size_t> map(cell_new_to_old.size() * k);
      for (std::size_t i = 0; i < cell_new_to_old.size(); ++i)
        for (int l = 0; l < k; ++l) map[i * k + l] = cell_new_to_old[i] * k + l;
      a->compact(map);
    }
  }
  // initialize() regrows attributes to the new sizes without touching their values.
  initialize(vertex_new_to_old.size(), cells);
  return std::vector<Id>(vertex_new_to_old.begin(), vertex_new_to_old.end());
}

template <int N>
std::vector<typename SimplexMesh<N>::Cell> SimplexMesh<N>::cells_array() const {
  std::vector<Cell> out;
  for (std::size_t c = 0; c < cell_capacity(); ++c)
    if (!is_cell_removed(Id(c))) out.push_back(cell(Id(c)));
  return out;
}

template <int N>
std::string SimplexMesh<N>::check_connectivity() const {
  std::ostringstream err;
  std::vector<std::vector<Id>> expected(vertex_capacity());
  std::int64_t live_cells = 0;
  std::map<std::array<Id, N>, Id> seen;
  std::map<std::array<Id, N - 1>, std::vector<int>> facet_signs;
  for (std::size_t c = 0; c < cell_capacity(); ++c) {
    if (is_cell_removed(Id(c))) continue;
    ++live_cells;
    Cell cv = cell(Id(c));
    for (Id v : cv) {
      if (v >= vertex_capacity() || is_vertex_removed(v)) {
        err << "cell " << c << " uses removed or unknown vertex " << v;
        return err.str();
      }
      expected[v].push_back(Id(c));
    }
    Cell sorted = cv;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
      err << "cell " << c << " is degenerate (repeated vertex)";
      return err.str();
    }
    if (auto [it, fresh] = seen.emplace(sorted, Id(c)); !fresh) {
      err << "cells " << it->second << " and " << c << " have the same vertices";
      return err.str();
    }
    for (int skip = 0; skip < N; ++skip) {
      std::array<Id, N - 1> f;
      int k = 0;
      for (int i = 0; i < N; ++i)
        if (i != skip) f[k++] = cv[i];
      const int sign = permutation_sign(f) * ((skip % 2) ? -1 : 1);
      std::sort(f.begin(), f.end());
      facet_signs[f].push_back(sign);
    }
  }
  for (const auto& [f, signs] : facet_signs) {
    if (signs.size() > 2) {
      err << "facet of vertex " << f[0] << " is shared by " << signs.size()
          << " cells (non-manifold)";
      return err.str();
    }
    if (signs.size() == 2 && signs[0] == signs[1]) {
      err << "facet of vertex " << f[0] << " has inconsistent orientation between its two cells";
      return err.str();
    }
  }
  std::int64_t live_vertices = 0;
  for (std::size_t v = 0; v < vertex_capacity(); ++v) {
    if (is_vertex_removed(Id(v))) {
      if (!vertex_cells(Id(v)).empty()) {
        err << "removed vertex " << v << " still has incident cells";
        return err.str();
      }
      continue;
    }
    ++live_vertices;
    if (vertex_cells(Id(v)) != expected[v]) {
      err << "incident cell list of vertex " << v << " does not match the cells";
      return err.str();
    }
    if (expected[v].empty()) {
      err << "live vertex " << v << " has no incident cell";
      return err.str();
    }
  }
  if (live_cells != m_live_cells.load() || live_vertices != m_live_vertices.load()) {
    err << "live counters out of date: cells " << m_live_cells.load() << " vs " << live_cells
        << ", vertices " << m_live_vertices.load() << " vs " << live_vertices;
    return err.str();
  }
  return {};
}

template class SimplexMesh<3>;
template class SimplexMesh<4>;

}  // namespace curvefem::meshing::editing
