#pragma once
// Isotropic remeshing [Botsch & Kobbelt 2004] as a mesh type other modules can constrain (thesis
// §4.4 "remeshing", §6.3): the passes of isotropic_remeshing() — split > 4/3 L, collapse < 4/5 L,
// valence flips, tangential relaxation — run on any IsotropicMesh. A derived mesh changes where
// vertices go (place_on_surface, and the SurfaceEditMesh placement hooks) and adds invariants
// (override `invariants`, calling this class's first); the schedule stays the same. The shell's
// section remesher (meshing/shell/section_remesh.hpp) is such a derived mesh.
//
// Conventions: positions in the `position` attribute; frozen vertices are never collapsed or
// moved; a placement that returns a non-finite point makes the operation fail (the degenerate
// face test of SurfaceEditMesh::invariants sees the NaN) and it is rolled back.

#include <string>
#include <utility>
#include <vector>

#include "meshing/editing/algorithms/surface_edit_mesh.hpp"
#include "meshing/editing/scheduler.hpp"

namespace curvefem::meshing::editing {

using PassLog = std::vector<std::pair<std::string, PassStats>>;

class IsotropicMesh : public SurfaceEditMesh {
 public:
  double high2 = 0;  // (4/3 L)²: collapses and flips may not create longer edges
  const SurfaceDistance* input = nullptr;  // default target of place_on_surface (none: stay)

  int target_valence(Id v) const { return frozen[v] ? 4 : 6; }
  // Change of the summed squared valence deviation of the 4 vertices if edge t is flipped.
  int deviation_change(const Tuple& t) const;

 protected:
  // Where a relaxed vertex goes after its tangential move to p: the closest point of `input`
  // (p itself without one). A non-finite result rejects the move.
  virtual Eigen::Vector3d place_on_surface(const Eigen::Vector3d& p) const;

  bool collapse_acceptable(const OperationRecord& r) const override;
  bool swap_acceptable(const Tuple& t) const override;
  Eigen::Vector3d smooth_position(Id v) const override;
};

// `iterations` rounds of split / collapse / flip / relax towards the target edge length (absolute)
// on a loaded mesh; one PassLog entry per scheduler pass. Consolidates after every round.
void isotropic_remeshing(IsotropicMesh& m, double target_edge, int iterations, int threads,
                         PassLog& log);

}  // namespace curvefem::meshing::editing
