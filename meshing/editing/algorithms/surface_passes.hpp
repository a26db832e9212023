#pragma once
// Internal: the three surface algorithms as functions on a loaded SurfaceEditMesh, each one
// scheduler configuration per pass (see the .cpp files, which read like their papers).

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "meshing/editing/algorithms/isotropic_remeshing.hpp"
#include "meshing/editing/algorithms/surface_edit_mesh.hpp"
#include "meshing/editing/scheduler.hpp"

namespace curvefem::meshing::editing {

using SurfacePass = ExecutePass<TriMesh>;

inline SurfacePass make_surface_pass(SurfaceEditMesh& m, int threads) {
  SurfacePass pass;
  pass.num_threads = threads;
  pass.position = [&m](Id v) { return m.position[v]; };
  return pass;
}

// Cheapest-first edge collapses until the face budget is met: the pass both decimation
// algorithms are (they differ in cost and placement only). Entries whose cost changed since they
// were queued are skipped; a success re-queues every edge of the kept vertex's star.
void run_collapse_pass(SurfaceEditMesh& m, const std::function<double(const TriMesh::Tuple&)>& cost,
                       std::size_t target_faces, int threads, const std::string& name,
                       PassLog& log);

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
