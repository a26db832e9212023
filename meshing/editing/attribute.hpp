#pragma once
// Typed per-simplex attributes that survive local operations and roll back with them.
//
// An attribute of dimension d lives on the mesh's d-simplices: d = 0 per vertex, d = cell
// dimension per cell, and in between (edges of a TriMesh; edges and faces of a TetMesh) one slot
// per (cell, local simplex) — the mesh writes every incident slot, so the value is the same
// whichever cell a tuple names. While an operation runs, the first write of any slot records the
// old value in the journal of the running thread; a rejected operation replays it backwards, so
// the attributes are bit-identical to before. New slots (new cells) are filled automatically:
// a cell inherits from the cell it was derived from, an edge or face from the same simplex
// before the operation (or, for the halves of a split simplex, from the simplex that was split);
// otherwise it gets the attribute's default. When a collapse merges two edges or faces into one,
// the first non-default value of the two survives on every slot of the merged simplex (so
// boundary and feature tags are kept); edge/face attribute types need operator==. Vertex attributes
// of new vertices start at the default; the operation's `after` hook sets them.

#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "meshing/editing/chunked_vector.hpp"
#include "meshing/editing/thread_slot.hpp"

namespace curvefem::meshing::editing {

class SimplexMeshBase;

class AttributeBase {
 public:
  AttributeBase(SimplexMeshBase& mesh, int dim);
  AttributeBase(const AttributeBase&) = delete;
  AttributeBase& operator=(const AttributeBase&) = delete;
  virtual ~AttributeBase();

  int dimension() const { return m_dim; }

  // Called by the mesh only.
  virtual void grow_to(std::size_t slots) = 0;
  virtual void rollback(int slot) = 0;
  virtual void clear_journal(int slot) = 0;
  virtual void copy_slot(std::size_t dst, std::size_t src) = 0;
  virtual void reset_slot(std::size_t dst) = 0;
  // dst = the first value among srcs that differs from the default (the default if none): when
  // a collapse merges two edges or faces, a tag set on either survives.
  virtual void merge_into(std::size_t dst, const std::vector<std::size_t>& srcs) = 0;
  // new_to_old[i] = old slot of new slot i (serial; journals must be empty).
  virtual void compact(const std::vector<std::size_t>& new_to_old) = 0;

 protected:
  bool journaling() const;
  std::size_t initial_slot_count() const;

 private:
  SimplexMeshBase* m_mesh;
  int m_dim;
};

template <class T>
class Attribute final : public AttributeBase {
 public:
  Attribute(SimplexMeshBase& mesh, int dim, T default_value = T{})
      : AttributeBase(mesh, dim), m_default(default_value), m_data(std::move(default_value)) {
    attach();
  }

  const T& operator[](std::size_t slot) const { return m_data[slot]; }

  // Writes one slot (journaled inside an operation). For edge/face attributes use the mesh's
  // set_edge/set_face, which write every incident slot.
  void set(std::size_t slot, const T& value) {
    if (journaling()) m_journal[current_thread_slot()].emplace_back(slot, m_data[slot]);
    m_data[slot] = value;
  }
  const T& default_value() const { return m_default; }

  void grow_to(std::size_t slots) override { m_data.grow_to(slots); }
  void rollback(int slot) override {
    auto& journal = m_journal[slot];
    for (auto it = journal.rbegin(); it != journal.rend(); ++it) m_data[it->first] = it->second;
    journal.clear();
  }
  void clear_journal(int slot) override { m_journal[slot].clear(); }
  void copy_slot(std::size_t dst, std::size_t src) override {
    const T value = m_data[src];
    set(dst, value);
  }
  void reset_slot(std::size_t dst) override { set(dst, m_default); }
  void merge_into(std::size_t dst, const std::vector<std::size_t>& srcs) override {
    T value = m_default;
    for (std::size_t s : srcs)
      if (!(m_data[s] == m_default)) {
        value = m_data[s];
        break;
      }
    set(dst, value);
  }
  void compact(const std::vector<std::size_t>& new_to_old) override {
    std::vector<T> kept(new_to_old.size());
    for (std::size_t i = 0; i < new_to_old.size(); ++i) kept[i] = m_data[new_to_old[i]];
    m_data.reset(kept.size());
    for (std::size_t i = 0; i < kept.size(); ++i) m_data[i] = std::move(kept[i]);
  }

 private:
  void attach() { grow_to(initial_slot_count()); }

  T m_default;
  ChunkedVector<T> m_data;
  std::array<std::vector<std::pair<std::size_t, T>>, k_max_threads> m_journal;
};

}  // namespace curvefem::meshing::editing
