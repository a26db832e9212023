#pragma once
// The triangle mesh the surface algorithms edit: positions, frozen (boundary) vertices, and the
// geometric invariants every algorithm shares — no fold, no degenerate face, and optionally the
// ε-envelope of the input. Algorithms derive from it and override the placement hooks.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/editing/algorithms/surface_distance.hpp"
#include "meshing/editing/tri_mesh.hpp"

namespace curvefem::meshing::editing {

class SurfaceEditMesh : public TriMesh {
 public:
  Attribute<Eigen::Vector3d> position{*this, 0, Eigen::Vector3d::Zero()};
  Attribute<char> frozen{*this, 0, 0};

  // Optional envelope: every new or moved face must stay within envelope_eps of it.
  // A face may turn by at most acos(min_normal_cos) in one operation (compared with the face it
  // came from); 90 degrees alone lets a sequence of operations fold a face over.
  double min_normal_cos = 0.5;

  const SurfaceDistance* envelope = nullptr;
  double envelope_eps = 0;

  // Loads a manifold, consistently oriented surface (InputError naming the first bad edge
  // otherwise); boundary vertices are frozen.
  void load(const SurfaceMesh& surface);
  // Compacts and exports the current surface.
  SurfaceMesh extract();

  Eigen::Vector3d face_normal(Id f) const;    // not normalized (twice the area)
  Eigen::Vector3d vertex_normal(Id v) const;  // area-weighted, normalized
  double edge_length2(const Tuple& t) const {
    return (position[t.vid] - position[other_vertex(t)]).squaredNorm();
  }
  // Valence on an edge-manifold surface: faces around v, plus one on the boundary (boundary
  // vertices are exactly the frozen ones here).
  int valence(Id v) const { return int(vertex_cells(v).size()) + (frozen[v] ? 1 : 0); }

  // Optional last check before a collapse (after the frozen-vertex test): false rejects it as
  // Rejection::before. Collapse passes use it to reserve their face budget
  // (shortest_edge_collapse.cpp).
  std::function<bool(const Tuple&)> collapse_admit;

 protected:
  // Placement hooks for the algorithms.
  virtual Eigen::Vector3d collapse_position(Id removed, Id kept) const {
    return 0.5 * (position[removed] + position[kept]);
  }
  virtual void collapse_update(const OperationRecord&) {}
  // Extra acceptance test after a collapse was placed (e.g. no long edge created).
  virtual bool collapse_acceptable(const OperationRecord&) const { return true; }
  virtual Eigen::Vector3d smooth_position(Id v) const { return position[v]; }
  virtual bool swap_acceptable(const Tuple&) const { return true; }

  bool split_edge_before(const Tuple& t) override;
  bool split_edge_after(const OperationRecord& r) override;
  bool collapse_edge_before(const Tuple& t) override;
  bool collapse_edge_after(const OperationRecord& r) override;
  bool swap_edge_before(const Tuple& t) override;
  bool swap_edge_after(const OperationRecord& r) override;
  bool smooth_before(const Tuple& t) override;
  bool smooth_after(const OperationRecord& r) override;
  bool invariants(const OperationRecord& r) override;

 private:
  enum class Kind { split, collapse, swap, smooth };
  struct Scratch {
    Kind kind = Kind::split;
    std::vector<Eigen::Vector3d> old_normals;
  };
  bool no_fold(const OperationRecord& r) const;
  bool close_normals(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;
  PerThread<Scratch> m_scratch;
};

}  // namespace curvefem::meshing::editing
