#pragma once
// Shell simplification on meshing/editing (thesis §4.3.2; reference-notes §3.6): shortest-first
// half-edge collapses of the middle surface that keep the kept vertex's pillar, accepted only if
// every new prism
//   I1  passes the exact 24-tet positivity test,
//   I2  keeps the input a section: every input triangle touching its canonical split tets has a
//       normal with cos(angle) > section_cos to each non-singular pillar,
//   I3  has base and top triangles that do not intersect the input (exact; pinch contact only),
// and the input faces covered by the removed prisms stay covered by the new ones. Singular
// vertices never move or disappear. Runs through the parallel scheduler.

#include "meshing/core/surface_mesh.hpp"
#include "meshing/editing/scheduler.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::meshing::shell {

struct SimplifyOptions {
  int threads = 1;
  double section_cos = 0.0;  // distortion bound on pillar/normal cosines (0: strict positivity)
  int rounds = 3;            // collapse passes (a pass re-seeds every edge)
};

struct SimplifyStats {
  int faces_before = 0, faces_after = 0;
  std::vector<editing::PassStats> passes;
  double seconds = 0;
};

Shell simplify_shell(const Shell& shell, const SurfaceMesh& input, const SimplifyOptions& options,
                     SimplifyStats& stats);

}  // namespace curvefem::meshing::shell
