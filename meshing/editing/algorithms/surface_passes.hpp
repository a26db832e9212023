#pragma once
// Internal: the three surface algorithms as functions on a loaded SurfaceEditMesh, each one
// scheduler configuration per pass (see the .cpp files, which read like their papers).

#include <string>
#include <utility>
#include <vector>

#include "meshing/editing/algorithms/surface_edit_mesh.hpp"
#include "meshing/editing/scheduler.hpp"

namespace curvefem::meshing::editing {

using SurfacePass = ExecutePass<TriMesh>;
using PassLog = std::vector<std::pair<std::string, PassStats>>;

inline SurfacePass make_surface_pass(SurfaceEditMesh& m, int threads) {
  SurfacePass pass;
  pass.num_threads = threads;
  pass.position = [&m](Id v) { return m.position[v]; };
  return pass;
}

// The mesh type each algorithm needs (QSlim adds quadrics); create with make_*_mesh.
std::unique_ptr<SurfaceEditMesh> make_shortest_collapse_mesh();
std::unique_ptr<SurfaceEditMesh> make_qslim_mesh();
std::unique_ptr<SurfaceEditMesh> make_isotropic_mesh();

void shortest_edge_collapse(SurfaceEditMesh& m, std::size_t target_faces, int threads,
                            PassLog& log);
void qslim(SurfaceEditMesh& m, std::size_t target_faces, int threads, PassLog& log);
void isotropic_remeshing(SurfaceEditMesh& m, const SurfaceDistance& input, double target_edge,
                         int iterations, int threads, PassLog& log);

}  // namespace curvefem::meshing::editing
