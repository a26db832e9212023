#pragma once
// The scheduler of local operations (thesis §6.2; reference-notes §8.3), for TriMesh and TetMesh.
//
// A pass is configured declaratively: named operations, a priority (max first), the work to
// renew after a success, a stale-priority filter, how to lock, when to stop. It seeds one
// priority queue per partition (Morton order of the vertices), runs one oneTBB task per queue,
// and takes vertex try-locks (never blocking) around every operation. An operation whose locks
// cannot be taken is deferred and retried up to max_retry_limit times, then handed to a serial
// tail after the parallel phase. An operation rejected by its hooks or invariants is NOT retried:
// it comes back only if a neighbouring success renews it (retrying every failure every round does
// not converge on large meshes).

#include <Eigen/Core>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "meshing/editing/tet_mesh.hpp"
#include "meshing/editing/tri_mesh.hpp"

namespace curvefem::meshing::editing {

struct PassStats {
  std::size_t attempted = 0;  // operations run (after locking and filtering)
  std::size_t succeeded = 0;
  std::size_t rejected_before = 0;     // user `before` hook said no
  std::size_t rejected_topology = 0;   // link condition, boundary, existing edge/face
  std::size_t rejected_after = 0;      // user `after` hook said no
  std::size_t rejected_invariant = 0;  // user invariants said no
  std::size_t stale_tuple = 0;         // tuple invalid when popped (its cell changed)
  std::size_t stale_priority = 0;      // should_process said no
  std::size_t lock_failures = 0;       // try-lock attempts that failed
  std::size_t serial_tail = 0;         // operations handed to the serial tail
  std::size_t epochs = 0;              // parallel epochs (see ExecutePass::epoch_fraction)
  std::size_t levels = 0;              // ordered levels (see ExecutePass::level_region)
  double seconds = 0;
  int threads = 1;

  std::size_t rejected() const {
    return rejected_before + rejected_topology + rejected_after + rejected_invariant;
  }
  std::string summary() const;
};

template <class Mesh>
class ExecutePass {
 public:
  using Tuple = typename Mesh::Tuple;
  using Work = std::pair<std::string, Tuple>;

  // name -> operation; returns the resulting tuple on success.
  std::map<std::string, std::function<std::optional<Tuple>(Mesh&, const Tuple&)>> operations;
  // Larger runs first. Called with the mesh locked around the tuple (or serially).
  std::function<double(const Mesh&, const std::string&, const Tuple&)> priority;
  // New work after a success (called while the operation's locks are still held).
  std::function<std::vector<Work>(const Mesh&, const std::string&, const Tuple&)>
      renew_neighbor_tuples;
  // Filters stale queue entries, e.g. when the recomputed priority differs from the queued one.
  std::function<bool(const Mesh&, const Work&, double queued_priority)> should_process;
  // Locks what the operation will touch (default: both edge endpoints and their one-rings;
  // lock_rings = 2 for the two-ring). Must only try-lock.
  std::function<bool(Mesh&, const Work&)> lock_vertices;
  int lock_rings = 1;
  // Checked after every success; must be thread-safe (read atomics such as num_cells()).
  std::function<bool(const Mesh&)> stopping_criterion;
  // Vertex positions for the Morton partition (optional; by vertex id otherwise).
  std::function<Eigen::Vector3d(Id)> position;

  // Ordered levels: a parallel pass whose mesh after the pass is the one-thread pass's, for
  // passes that renew nothing, change no cell (vertex smoothing) and have neither
  // `should_process` nor `stopping_criterion`. The work is taken in the order one thread would run
  // it (the same queue); an operation's level is one more than the highest level of an earlier
  // operation whose region shares a vertex with its own; the levels run one after another and
  // the operations of a level in parallel, without locks. The result equals the serial pass's
  // PROVIDED each operation reads and writes only data of its region's vertices and of cells
  // all of whose vertices are in it, or data no operation of the pass writes — the user's
  // argument, as for the refusal memo. `level_region(mesh, t, out)` fills `out` with the
  // region's vertices, and may name other shared data by ids from vertex_capacity() on (e.g.
  // vertex_capacity() + i for entry i of a user array). Used when set and num_threads > 1;
  // otherwise ignored.
  std::function<void(const Mesh&, const Tuple&, std::vector<Id>&)> level_region;
  // Tests of a region argument: each level runs on one thread in the reverse of the serial order.
  // Operations that commute as claimed give the same mesh; a region that misses a dependence
  // swaps two dependent operations (two threads rarely run them in the wrong order).
  bool reverse_levels = false;

  int num_threads = 1;
  int max_retry_limit = 10;
  // Approximate global order with parallel tasks: the pass runs in epochs; each epoch first
  // estimates the priority above which `epoch_fraction` of all queued work lies, then every task
  // runs only its entries at or above it (renewed ones included). Without this, one partition
  // can run far down its queue while another still holds better work — e.g. QSlim spending the
  // face budget on costly collapses in one half while zero-cost ones wait in the other.
  // 0 disables (one epoch). Serial runs are always in exact priority order.
  double epoch_fraction = 0.05;

  PassStats run(Mesh& mesh, const std::vector<Work>& work);
};

// Partition of the vertices into `parts` blocks of consecutive Morton codes (reference-notes §8.3).
std::vector<int> morton_partition(std::size_t num_vertices,
                                  const std::function<Eigen::Vector3d(Id)>& position, int parts);

extern template class ExecutePass<TriMesh>;
extern template class ExecutePass<TetMesh>;

}  // namespace curvefem::meshing::editing
