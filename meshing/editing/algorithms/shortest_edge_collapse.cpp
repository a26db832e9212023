// Shortest-edge collapse [Hoppe 1996]: repeatedly collapse the shortest edge to its midpoint
// until the face budget is met. The only operation is the collapse; its priority is the negated
// squared length; after a collapse the edges around the kept vertex are re-queued with their new
// lengths, and queue entries whose length changed since they were queued are skipped.

#include <condition_variable>
#include <memory>
#include <mutex>

#include "meshing/editing/algorithms/surface_passes.hpp"

namespace curvefem::meshing::editing {

std::unique_ptr<SurfaceEditMesh> make_shortest_collapse_mesh() {
  return std::make_unique<SurfaceEditMesh>();
}

void run_collapse_pass(SurfaceEditMesh& m, const std::function<double(const TriMesh::Tuple&)>& cost,
                       std::size_t target_faces, int threads, const std::string& name,
                       PassLog& log) {
  SurfacePass pass = make_surface_pass(m, threads);
  // The face budget: a collapse reserves the faces it removes (2, or 1 on a boundary edge) as the
  // last check before it (Rejection::before when none is left), so parallel tasks cannot all pass
  // the stopping check at target + 2 and end below the target together. A task finding the budget
  // spent while another's reservation is in flight waits for its outcome (that task holds its
  // locks already and waits for nothing), so a failed collapse hands its faces on. A collapse may
  // start while any budget is left, as the serial check `faces <= target` allows: the result has
  // the serial run's face count.
  struct Budget {
    std::mutex mutex;
    std::condition_variable changed;
    long long left = 0;
    int holders = 0;
  };
  auto budget = std::make_shared<Budget>();
  budget->left = static_cast<long long>(m.num_cells()) - static_cast<long long>(target_faces);
  m.collapse_admit = [&m, budget](const TriMesh::Tuple& t) {
    std::unique_lock<std::mutex> lock(budget->mutex);
    budget->changed.wait(lock, [&] { return budget->left >= 1 || budget->holders == 0; });
    if (budget->left < 1) return false;
    budget->left -= m.is_boundary_edge(t) ? 1 : 2;
    ++budget->holders;
    return true;
  };
  pass.operations["collapse"] = [&m, budget](TriMesh&, const TriMesh::Tuple& t) {
    const long long removes = m.is_valid(t) && m.is_boundary_edge(t) ? 1 : 2;
    auto result = m.collapse_edge(t);
    const Rejection why = m.last_rejection();
    if (result || (why != Rejection::before && why != Rejection::invalid_tuple)) {
      {  // the collapse had a reservation: keep it, or give it back
        std::lock_guard<std::mutex> lock(budget->mutex);
        if (!result) budget->left += removes;
        --budget->holders;
      }
      budget->changed.notify_all();
    }
    return result;
  };
  pass.priority = [&cost](const TriMesh&, const std::string&, const TriMesh::Tuple& t) {
    return -cost(t);
  };
  pass.should_process = [&cost](const TriMesh&, const SurfacePass::Work& w, double queued) {
    return -cost(w.second) == queued;
  };
  pass.renew_neighbor_tuples = [&m](const TriMesh&, const std::string&,
                                    const TriMesh::Tuple& kept) {
    std::vector<SurfacePass::Work> work;
    for (const auto& e : m.edges_of_faces(m.vertex_cells(kept.vid)))
      work.emplace_back("collapse", e);
    return work;
  };
  pass.stopping_criterion = [&m, target_faces](const TriMesh&) {
    return m.num_cells() <= target_faces;
  };
  // A pass ends when its queue is empty. An edge refused once (its collapse would fold a face,
  // say) is queued again only when a collapse touches it, so in parallel, where the order
  // differs from run to run, a pass can end above the target with collapses still possible: a
  // 6 x 6-quad box under QSlim on 2 threads ended at 42 faces of 40 about once in 50 runs
  // (EditingAlgorithms.QSlimSimplifiesABoxExactly). Then every edge is queued again, while a
  // pass collapses something and the target is not reached.
  for (int round = 0; round < 8; ++round) {
    std::vector<SurfacePass::Work> work;
    for (const auto& e : m.get_edges()) work.emplace_back("collapse", e);
    const PassStats stats = pass.run(m, work);
    log.emplace_back(name, stats);
    if (m.num_cells() <= target_faces || stats.succeeded == 0) break;
  }
  m.collapse_admit = nullptr;
}

void shortest_edge_collapse(SurfaceEditMesh& m, std::size_t target_faces, int threads,
                            PassLog& log) {
  run_collapse_pass(
      m, [&m](const TriMesh::Tuple& t) { return m.edge_length2(t); }, target_faces, threads,
      "collapse", log);
}

}  // namespace curvefem::meshing::editing
