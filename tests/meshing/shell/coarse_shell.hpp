// The shell `curvefem shell` builds (default options, simplified with growth 0.1 of the bbox),
// on one thread so that tests get the same coarse surface every run.
#pragma once

#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"

namespace curvefem::test {

inline meshing::shell::Shell coarse_shell(const SurfaceMesh& s) {
  namespace sh = meshing::shell;
  sh::ShellOptions o;
  o.threads = 1;
  sh::ShellStats stats;
  sh::Shell shell = sh::build_shell(s, o, stats);
  sh::SimplifyOptions so;
  so.threads = 1;
  so.zoom = 0.1 * bbox_longest_edge(s.V);
  sh::SimplifyStats ss;
  return sh::simplify_shell(shell, s, so, ss);
}

}  // namespace curvefem::test
