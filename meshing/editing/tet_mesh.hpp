#pragma once
// Tetrahedral mesh for declarative editing (thesis chapter 6; reference-notes §8.1).
//
// Tuple = (vertex, local edge 0..5, local face 0..3, tetrahedron, hash) with local edges
// {01,12,02,03,13,23} and local faces {012,023,013,123}; the vertex lies on the edge, the edge on
// the face. Tets are stored positively oriented; every operation builds its new tets by
// substituting vertices in an old tet that shares a cavity-boundary face with it, which keeps
// that orientation without looking at coordinates.
//
// Operations: split_edge, collapse_edge (link condition), swap_face_23 (2-3), swap_edge_32 (3-2),
// swap_edge_44 (4-4), smooth_vertex — each with before/after hooks, invariants and exact
// rollback, as in TriMesh.

#include <optional>
#include <vector>

#include "meshing/editing/simplex_mesh.hpp"

namespace curvefem::meshing::editing {

class TetMesh : public SimplexMesh<4> {
 public:
  struct Tuple {
    Id vid = k_no_id;
    std::int8_t local_edge = -1;
    std::int8_t local_face = -1;
    Id tid = k_no_id;
    std::uint32_t hash = 0;
    bool operator==(const Tuple&) const = default;
  };

  TetMesh() = default;

  // Tuple at local vertex lv on local edge le of local face lf of tet t.
  Tuple tuple(Id t, int lv, int le, int lf) const;
  std::optional<Tuple> edge_tuple(Id a, Id b) const;
  std::optional<Tuple> face_tuple(Id a, Id b, Id c) const;
  bool is_valid(const Tuple& t) const;

  Tuple switch_vertex(const Tuple& t) const;
  Tuple switch_edge(const Tuple& t) const;
  Tuple switch_face(const Tuple& t) const;
  std::optional<Tuple> switch_tetrahedron(const Tuple& t) const;

  Id other_vertex(const Tuple& t) const { return switch_vertex(t).vid; }
  std::array<Id, 3> face_vertices(const Tuple& t) const;
  bool is_boundary_face(const Tuple& t) const;
  bool is_boundary_edge(const Tuple& t) const;

  std::vector<Tuple> get_edges() const;
  std::vector<Tuple> get_faces() const;
  std::vector<Tuple> get_vertices() const;
  std::vector<Tuple> get_tets() const;
  std::vector<Tuple> edges_of_tets(const std::vector<Id>& tets) const;
  std::vector<Tuple> faces_of_tets(const std::vector<Id>& tets) const;

  std::array<Id, 2> lock_seeds(const Tuple& t) const { return {t.vid, other_vertex(t)}; }

  // Tuple at the new vertex (on the half towards the old t.vid).
  std::optional<Tuple> split_edge(const Tuple& t);
  // t.vid is removed and merged into the other endpoint; tuple at the kept vertex.
  std::optional<Tuple> collapse_edge(const Tuple& t);
  // 2-3: the interior face of t becomes an edge between the two opposite vertices; tuple on it.
  std::optional<Tuple> swap_face_23(const Tuple& t);
  // 3-2: the interior edge of t with exactly 3 tets becomes a face; tuple on that face.
  std::optional<Tuple> swap_edge_32(const Tuple& t);
  // 4-4: the interior edge of t with exactly 4 tets is replaced by the diagonal through the
  // third vertex of t's face; tuple on the new edge.
  std::optional<Tuple> swap_edge_44(const Tuple& t);
  std::optional<Tuple> smooth_vertex(const Tuple& t);

  const OperationRecord& operation_record() const;

  template <class T>
  void set_face(Attribute<T>& attr, const Tuple& t, const T& value) {
    const auto f = face_vertices(t);
    set_subsimplex(attr, std::span<const Id>(f.data(), 3), value);
  }
  template <class T>
  const T& get_face(const Attribute<T>& attr, const Tuple& t) const {
    return attr[slot(t.tid, t.local_face, 2)];
  }
  template <class T>
  void set_edge(Attribute<T>& attr, const Tuple& t, const T& value) {
    const Id e[2] = {t.vid, other_vertex(t)};
    set_subsimplex(attr, std::span<const Id>(e, 2), value);
  }
  template <class T>
  const T& get_edge(const Attribute<T>& attr, const Tuple& t) const {
    return attr[slot(t.tid, t.local_edge, 1)];
  }

 protected:
  virtual bool split_edge_before(const Tuple&) { return true; }
  virtual bool split_edge_after(const OperationRecord&) { return true; }
  virtual bool collapse_edge_before(const Tuple&) { return true; }
  virtual bool collapse_edge_after(const OperationRecord&) { return true; }
  virtual bool swap_face_before(const Tuple&) { return true; }
  virtual bool swap_face_after(const OperationRecord&) { return true; }
  virtual bool swap_edge_before(const Tuple&) { return true; }  // 3-2 and 4-4
  virtual bool swap_edge_after(const OperationRecord&) { return true; }
  virtual bool smooth_before(const Tuple&) { return true; }
  virtual bool smooth_after(const OperationRecord&) { return true; }
  virtual bool invariants(const OperationRecord&) { return true; }

 private:
  std::optional<Tuple> finish(OperationRecord& rec, bool after_ok, const Tuple& result);
  int local_vertex(Id t, Id v) const;
  // Tuple at a on edge (a, b) of face (a, b, c) in tet t.
  Tuple tuple_on(Id t, Id a, Id b, Id c) const;
  // Ring of the opposite vertices around interior edge (a, b), cyclic; empty if boundary.
  std::vector<Id> edge_ring(Id a, Id b, const std::vector<Id>& tets) const;

  std::array<OperationRecord, k_max_threads> m_records;
};

}  // namespace curvefem::meshing::editing
