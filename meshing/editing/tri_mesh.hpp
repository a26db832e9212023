#pragma once
// Triangle mesh for declarative editing (thesis chapter 6; reference-notes §8).
//
// Tuple = (vertex, local edge, face, face hash): local edge i of a face is the edge opposite its
// local vertex i. A tuple is valid while its face is alive and unchanged (same hash); every
// operation replaces the faces it touches, so stale tuples are rejected in O(1).
//
// Operations: split_edge, collapse_edge, swap_edge, smooth_vertex. Each runs
//   before(tuple) -> topological change -> after(record) -> invariants(record)
// and restores connectivity and every attribute exactly when any step says no. Derive from
// TriMesh and override the hooks; attributes are members constructed with `*this`.

#include <optional>
#include <vector>

#include "meshing/editing/simplex_mesh.hpp"

namespace curvefem::meshing::editing {

class TriMesh : public SimplexMesh<3> {
 public:
  struct Tuple {
    Id vid = k_no_id;
    std::int8_t local_edge = -1;
    Id fid = k_no_id;
    std::uint32_t hash = 0;
    bool operator==(const Tuple&) const = default;
  };

  TriMesh() = default;

  // Tuple at local vertex lv of face f on local edge le (le != lv).
  Tuple tuple(Id f, int local_vertex, int local_edge) const;
  // Tuple at vertex a on edge (a, b), in the smallest face containing it.
  std::optional<Tuple> edge_tuple(Id a, Id b) const;
  bool is_valid(const Tuple& t) const;

  Tuple switch_vertex(const Tuple& t) const;
  Tuple switch_edge(const Tuple& t) const;
  std::optional<Tuple> switch_face(const Tuple& t) const;

  Id other_vertex(const Tuple& t) const { return switch_vertex(t).vid; }
  bool is_boundary_edge(const Tuple& t) const;
  bool is_boundary_vertex(Id v) const;

  // One tuple per edge / vertex / face of the live mesh.
  std::vector<Tuple> get_edges() const;
  std::vector<Tuple> get_vertices() const;
  std::vector<Tuple> get_faces() const;
  // Every edge of the given faces once (the usual renewal set after an operation).
  std::vector<Tuple> edges_of_faces(const std::vector<Id>& faces) const;
  // Edges incident to v, one tuple each, all with vid == v.
  std::vector<Tuple> vertex_edges(Id v) const;

  // Vertices the default scheduler lock starts from: both edge endpoints.
  std::array<Id, 2> lock_seeds(const Tuple& t) const { return {t.vid, other_vertex(t)}; }

  // Operations. Each returns the tuple described below, or nullopt (last_rejection() says why).
  // Tuple at the new vertex, on the half towards the old t.vid.
  std::optional<Tuple> split_edge(const Tuple& t);
  // Vertex t.vid is removed and merged into the other endpoint; tuple at the kept vertex.
  std::optional<Tuple> collapse_edge(const Tuple& t);
  // Replaces an interior edge by the other diagonal of its two faces; tuple on the new edge.
  std::optional<Tuple> swap_edge(const Tuple& t);
  // No topological change: `after` moves the vertex; tuple at the vertex.
  std::optional<Tuple> smooth_vertex(const Tuple& t);

  // The record of the operation running on this thread (valid inside hooks).
  const OperationRecord& operation_record() const;

  // Write an edge attribute on every face slot of edge t.
  template <class T>
  void set_edge(Attribute<T>& attr, const Tuple& t, const T& value) {
    const Id e[2] = {t.vid, other_vertex(t)};
    set_subsimplex(attr, std::span<const Id>(e, 2), value);
  }
  template <class T>
  const T& get_edge(const Attribute<T>& attr, const Tuple& t) const {
    return attr[slot(t.fid, t.local_edge, 1)];
  }

 protected:
  virtual bool split_edge_before(const Tuple&) { return true; }
  virtual bool split_edge_after(const OperationRecord&) { return true; }
  virtual bool collapse_edge_before(const Tuple&) { return true; }
  virtual bool collapse_edge_after(const OperationRecord&) { return true; }
  virtual bool swap_edge_before(const Tuple&) { return true; }
  virtual bool swap_edge_after(const OperationRecord&) { return true; }
  virtual bool smooth_before(const Tuple&) { return true; }
  virtual bool smooth_after(const OperationRecord&) { return true; }
  // Runs after every `after` hook on record.new_cells.
  virtual bool invariants(const OperationRecord&) { return true; }

 private:
  std::optional<Tuple> finish(OperationRecord& rec, bool after_ok, const Tuple& result);
  int local_vertex(Id f, Id v) const;
  int local_edge_of(Id f, Id a, Id b) const;

  std::array<OperationRecord, k_max_threads> m_records;
};

}  // namespace curvefem::meshing::editing
