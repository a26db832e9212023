#pragma once
// Connectivity shared by TriMesh (N = 3) and TetMesh (N = 4): cells of N vertex ids, for every
// vertex the sorted list of incident cells, removal flags, and a per-cell version hash that
// makes stale tuples cheap to detect. Ids are never reused until consolidate(), so a cell's
// vertex list is immutable once created; only its (atomic) state changes.
//
// Every local operation is one "replacement": remove some cells, add new ones (each derived from
// an old cell by replacing vertices, which keeps orientation), possibly add or remove vertices.
// The mesh records what it needs to undo it exactly; derived classes wrap it with the user's
// before/after/invariant hooks and call commit or rollback.

#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "meshing/editing/attribute.hpp"

namespace curvefem::meshing::editing {

using Id = std::uint32_t;
inline constexpr Id k_no_id = 0xffffffffu;

// Why the last operation on this thread slot was rejected.
enum class Rejection : std::uint8_t { none, invalid_tuple, before, topology, after, invariant };

// What an operation did; passed to the after hook and the invariants.
struct OperationRecord {
  // split: the split edge; collapse: v0 removed and merged into v1; swap: the old edge;
  // smooth: v0 is the vertex.
  Id v0 = k_no_id, v1 = k_no_id;
  Id new_vertex = k_no_id;                       // split
  std::array<Id, 2> new_edge{k_no_id, k_no_id};  // swap (triangles, 2-3 and 4-4 on tets)
  std::vector<Id> old_cells;                     // removed (still readable, marked removed)
  std::vector<Id> new_cells;                     // created (for smoothing: the star of v0)
  // Every live cell whose shape the `after` hook can change by moving the operation's vertices:
  // the new cells, plus for a collapse the rest of the kept vertex's star. Invariants on
  // geometry (orientation, envelope, quality) must look at all of them.
  std::vector<Id> affected_cells;
};

class SimplexMeshBase {
 public:
  SimplexMeshBase() = default;
  SimplexMeshBase(const SimplexMeshBase&) = delete;
  SimplexMeshBase& operator=(const SimplexMeshBase&) = delete;
  virtual ~SimplexMeshBase() = default;

  // Number of storage slots an attribute of dimension dim needs now.
  virtual std::size_t attribute_slot_count(int dim) const = 0;
  // True while an operation runs on the calling thread slot (attribute writes are journaled).
  virtual bool operation_active() const = 0;

 protected:
  friend class AttributeBase;
  std::vector<AttributeBase*> m_attributes;
};

template <int N>
class SimplexMesh : public SimplexMeshBase {
  static_assert(N == 3 || N == 4);

 public:
  using Cell = std::array<Id, N>;
  static constexpr int k_dim = N - 1;

  SimplexMesh();
  ~SimplexMesh() override;

  // Replaces the mesh (serial). Vertex ids are 0..num_vertices-1; cells are consistently
  // oriented (positive volume for tets, outward normals for closed surfaces).
  void initialize(std::size_t num_vertices, const std::vector<Cell>& cells);

  std::size_t vertex_capacity() const { return m_vertices.size(); }
  std::size_t cell_capacity() const { return m_cells.size(); }
  std::size_t num_vertices() const { return static_cast<std::size_t>(m_live_vertices.load()); }
  std::size_t num_cells() const { return static_cast<std::size_t>(m_live_cells.load()); }
  bool is_vertex_removed(Id v) const { return m_vertices[v].removed; }
  bool is_cell_removed(Id c) const {
    return (m_cells[c].state.load(std::memory_order_acquire) & 1u) != 0;
  }
  std::uint32_t cell_hash(Id c) const {
    return m_cells[c].state.load(std::memory_order_acquire) >> 1;
  }
  const Cell& cell(Id c) const { return m_cells[c].v; }
  // Sorted ids of the live cells incident to v.
  const std::vector<Id>& vertex_cells(Id v) const { return m_vertices[v].cells; }

  std::vector<Id> live_vertices() const;
  std::vector<Id> live_cells() const;
  // Sorted neighbours of v (vertices sharing a cell with v, v excluded).
  std::vector<Id> one_ring(Id v) const;
  // Sorted live cells containing every vertex of `verts`.
  std::vector<Id> cells_containing(std::span<const Id> verts) const;
  bool is_boundary_facet(std::span<const Id> facet) const;

  // Compacts ids (serial): removed vertices and cells disappear, attributes follow, every tuple
  // becomes invalid. Returns old id of every new vertex.
  std::vector<Id> consolidate();

  // Compact copy of the live cells in the current vertex numbering (consolidate first for a
  // dense numbering).
  std::vector<Cell> cells_array() const;

  // Structural self-check: incident lists match the cells, no duplicate or degenerate cells,
  // every facet in at most two cells, neighbouring cells induce opposite orientations on their
  // shared facet. Returns an empty string when valid, else the first defect found.
  std::string check_connectivity() const;

  // Vertex try-locks (never blocking). The calling thread slot owns what it locks until
  // release_vertex_locks(); locking an owned vertex again succeeds.
  bool try_lock_vertex(Id v);
  // Locks the vertices of `seeds` and `rings` rings around them (0: seeds only).
  bool try_lock_region(std::span<const Id> seeds, int rings);
  void release_vertex_locks();

  // Attribute slot of the local sub-simplex `local` (of dimension dim) of cell c.
  static std::size_t slot(Id c, int local, int dim);
  static int slots_per_cell(int dim);
  // Local vertex indices of sub-simplex `local` of dimension dim (1 <= dim <= N-2).
  static std::span<const int> local_simplex(int dim, int local);

  std::size_t attribute_slot_count(int dim) const override;
  bool operation_active() const override;

  // Why the last operation on this thread slot was rejected (none after a success).
  Rejection last_rejection() const;

  // Writes value into every slot of the simplex `verts` (dimension verts.size()-1, an edge or
  // a face below the cell dimension) in all incident cells.
  template <class T>
  void set_subsimplex(Attribute<T>& attr, std::span<const Id> verts, const T& value) {
    for (Id c : cells_containing(verts))
      attr.set(slot(c, local_index_of(c, verts), int(verts.size()) - 1), value);
  }
  // Local index of the sub-simplex `verts` within cell c (must be contained).
  int local_index_of(Id c, std::span<const Id> verts) const;

 protected:
  struct NewCell {
    Cell v;
    Id parent;  // the old cell it was derived from (attributes of dimension N-1 copied)
  };
  struct Replacement {
    std::vector<Id> old_cells;
    std::vector<NewCell> new_cells;
    Id collapse_from = k_no_id, collapse_to = k_no_id;  // edge collapse: from merged into to
    Id split_vertex = k_no_id, split_a = k_no_id, split_b = k_no_id;  // edge split
  };

  void begin_operation();
  Id allocate_vertex();
  // Applies the replacement and returns the new cell ids (in the order given).
  std::vector<Id> replace(const Replacement& r);
  void commit_operation();
  void rollback_operation(Rejection why);
  void reject(Rejection why);

  // Link condition for collapsing edge (a, b), boundary handled with a virtual vertex.
  bool link_condition(Id a, Id b) const;
  // c's vertices with `from` replaced by `to`.
  static Cell replaced(const Cell& c, Id from, Id to);

 private:
  struct VertexRecord {
    std::vector<Id> cells;
    bool removed = false;
  };
  struct CellRecord {
    Cell v{};
    std::atomic<std::uint32_t> state{0};  // (hash << 1) | removed
    CellRecord() = default;
    CellRecord(const CellRecord& o) : v(o.v), state(o.state.load()) {}
    CellRecord& operator=(const CellRecord& o) {
      v = o.v;
      state.store(o.state.load());
      return *this;
    }
  };
  struct LockWord {
    std::atomic<int> owner{0};
    LockWord() = default;
    LockWord(const LockWord&) : owner(0) {}
    LockWord& operator=(const LockWord&) {
      owner.store(0);
      return *this;
    }
  };
  struct UndoLog {
    bool active = false;
    Rejection last = Rejection::none;
    std::vector<std::pair<Id, VertexRecord>> saved_vertices;
    std::vector<Id> old_cells, new_cells, new_vertices, removed_vertices;
  };

  void inherit_attributes(const Replacement& r, const std::vector<Id>& new_ids);
  void grow_cell_attributes(std::size_t cell_capacity);

  ChunkedVector<VertexRecord> m_vertices;
  ChunkedVector<CellRecord> m_cells;
  ChunkedVector<LockWord> m_locks;
  std::atomic<std::int64_t> m_live_vertices{0}, m_live_cells{0};
  std::array<UndoLog, k_max_threads> m_undo;
  std::array<std::vector<Id>, k_max_threads> m_held_locks;
};

extern template class SimplexMesh<3>;
extern template class SimplexMesh<4>;

}  // namespace curvefem::meshing::editing
