#pragma once
// Transitional (issue 23): φ⁻¹ built from a Shell in one call, for callers written against the
// former `mapping::BoundaryInverse::through_shell` (tools/curvefem/cmd_run.cpp until it moves to
// pipeline/). mapping/ no longer knows the shell: it takes the shell's fibers
// (meshing/shell/fibers_of.hpp). Header-only and included by no library of meshing/ (it reaches
// up to mapping/): delete it once its last caller uses
//   mapping::BoundaryInverse(map, meshing::shell::fibers_of(shell, input), input)
// directly.
#include "mapping/boundary_inverse.hpp"
#include "meshing/shell/fibers_of.hpp"

namespace curvefem::meshing::shell {

inline mapping::BoundaryInverse through_shell(const BoundaryMap& map, const Shell& shell,
                                              const SurfaceMesh& input) {
  return mapping::BoundaryInverse(map, fibers_of(shell, input), input);
}

}  // namespace curvefem::meshing::shell
