#include "meshing/editing/scheduler.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <limits>
#include <mutex>
#include <numeric>
#include <unordered_map>

#include "meshing/core/error.hpp"
#include "meshing/core/morton.hpp"

// oneTBB's library is not built with ThreadSanitizer, so TSan cannot see that the tasks of a
// parallel_for start after the code before it and finish before arena.execute returns. These
// annotations state exactly those two happens-before edges (and nothing else).
#if defined(__SANITIZE_THREAD__)
extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);
#define CF_TSAN_ACQUIRE(addr) __tsan_acquire(addr)
#define CF_TSAN_RELEASE(addr) __tsan_release(addr)
#else
#define CF_TSAN_ACQUIRE(addr) ((void)(addr))
#define CF_TSAN_RELEASE(addr) ((void)(addr))
#endif

namespace curvefem::meshing::editing {

std::string PassStats::summary() const {
  char buf[320];
  std::snprintf(buf, sizeof(buf),
                "%zu attempted, %zu succeeded, %zu rejected (before %zu, topology %zu, after %zu, "
                "invariant %zu), "
                "%zu stale, %zu lock failures, %zu serial tail, %zu levels, %.3f s on %d thread(s)",
                attempted, succeeded, rejected(), rejected_before, rejected_topology,
                rejected_after, rejected_invariant, stale_tuple + stale_priority, lock_failures,
                serial_tail, levels, seconds, threads);
  return buf;
}

namespace {

void add(PassStats& into, const PassStats& s) {
  into.attempted += s.attempted;
  into.succeeded += s.succeeded;
  into.rejected_before += s.rejected_before;
  into.rejected_topology += s.rejected_topology;
  into.rejected_after += s.rejected_after;
  into.rejected_invariant += s.rejected_invariant;
  into.stale_tuple += s.stale_tuple;
  into.stale_priority += s.stale_priority;
  into.lock_failures += s.lock_failures;
  into.serial_tail += s.serial_tail;
  into.levels += s.levels;
}

// body(p) for p in [0, threads) on the arena's threads, each isolated in thread slot p (the
// engine's per-thread journals and locks), with the fork and join annotated for TSan.
template <class Body>
void run_in_slots(tbb::task_arena& arena, int threads, const Body& body) {
  int fork = 0, join = 0;
  CF_TSAN_RELEASE(&fork);
  arena.execute([&] {
    tbb::parallel_for(0, threads, [&](int p) {
      CF_TSAN_ACQUIRE(&fork);
      tbb::this_task_arena::isolate([&] {
        ThreadSlotScope slot(p);
        body(p);
      });
      CF_TSAN_RELEASE(&join);
    });
  });
  CF_TSAN_ACQUIRE(&join);
}

// Counts why an operation was refused.
void count_rejection(PassStats& st, Rejection why) {
  switch (why) {
    case Rejection::before:
      ++st.rejected_before;
      break;
    case Rejection::topology:
      ++st.rejected_topology;
      break;
    case Rejection::after:
      ++st.rejected_after;
      break;
    case Rejection::invariant:
      ++st.rejected_invariant;
      break;
    default:
      ++st.stale_tuple;
      break;
  }
}

}  // namespace

std::vector<int> morton_partition(std::size_t n, const std::function<Eigen::Vector3d(Id)>& position,
                                  int parts) {
  std::vector<int> part(n, 0);
  if (n == 0 || parts <= 1) return part;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  std::vector<Eigen::Vector3d> p(n);
  for (std::size_t v = 0; v < n; ++v) {
    p[v] = position(Id(v));
    lo = lo.cwiseMin(p[v]);
    hi = hi.cwiseMax(p[v]);
  }
  const double extent = std::max((hi - lo).maxCoeff(), 1e-300);
  std::vector<std::uint64_t> code(n);
  for (std::size_t v = 0; v < n; ++v) {
    code[v] = morton_key(p[v], lo, extent);
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return code[a] < code[b]; });
  for (std::size_t r = 0; r < n; ++r) part[order[r]] = int(r * std::size_t(parts) / n);
  return part;
}

template <class Mesh>
PassStats ExecutePass<Mesh>::run(Mesh& mesh, const std::vector<Work>& work) {
  const auto t0 = std::chrono::steady_clock::now();
  struct Entry {
    double priority;
    int op;
    Tuple t;
    int retries;
    bool operator<(const Entry& o) const { return priority < o.priority; }
  };
  // A binary max-heap whose storage can be sampled (for the epoch thresholds).
  struct Queue {
    std::vector<Entry> heap;
    bool empty() const { return heap.empty(); }
    std::size_t size() const { return heap.size(); }
    const Entry& top() const { return heap.front(); }
    void push(const Entry& e) {
      heap.push_back(e);
      std::push_heap(heap.begin(), heap.end());
    }
    void pop() {
      std::pop_heap(heap.begin(), heap.end());
      heap.pop_back();
    }
  };

  std::vector<std::string> names;
  std::vector<const std::function<std::optional<Tuple>(Mesh&, const Tuple&)>*> fns;
  std::unordered_map<std::string, int> index;
  for (const auto& [name, fn] : operations) {
    index[name] = int(names.size());
    names.push_back(name);
    fns.push_back(&fn);
  }
  auto op_index = [&](const std::string& name) {
    auto it = index.find(name);
    CF_VERIFY(it != index.end(), "ExecutePass: unknown operation '" + name + "'");
    return it->second;
  };
  auto prio = [&](int op, const Tuple& t) { return priority ? priority(mesh, names[op], t) : 0.0; };

  const int threads = std::clamp(num_threads, 1, k_max_threads);
  std::vector<Queue> queues(threads);
  std::vector<int> part;
  if (threads > 1) {
    if (position) {
      part = morton_partition(mesh.vertex_capacity(), position, threads);
    } else {
      part.resize(mesh.vertex_capacity());
      for (std::size_t v = 0; v < part.size(); ++v) part[v] = int(v * threads / part.size());
    }
  }
  // Seeding: priorities are computed in parallel (read-only), then pushed in input order.
  std::vector<int> ops(work.size());
  for (std::size_t i = 0; i < work.size(); ++i) ops[i] = op_index(work[i].first);
  std::vector<double> priorities(work.size());
  auto seed = [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) priorities[i] = prio(ops[i], work[i].second);
  };
  if (threads > 1) {
    tbb::task_arena seeding(threads);
    seeding.execute([&] {
      tbb::parallel_for(
          tbb::blocked_range<std::size_t>(0, work.size(), 4096),
          [&](const tbb::blocked_range<std::size_t>& r) { seed(r.begin(), r.end()); });
    });
  } else {
    seed(0, work.size());
  }
  if (level_region && threads > 1 && !renew_neighbor_tuples && !should_process &&
      !stopping_criterion) {
    // Ordered levels: the one-thread pass's order is its queue's pop order (the same pushes into
    // the same heap; with nothing renewed it does not depend on the outcomes).
    Queue q;
    for (std::size_t i = 0; i < work.size(); ++i)
      q.push(Entry{priorities[i], ops[i], work[i].second, 0});
    std::vector<Entry> order;
    order.reserve(q.size());
    while (!q.empty()) {
      order.push_back(q.top());
      q.pop();
    }
    // Levels: one more than the highest level of an earlier entry sharing a region vertex.
    std::vector<int> last(mesh.vertex_capacity(), 0), level(order.size(), 0);
    std::vector<Id> region;
    int levels = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
      region.clear();
      if (mesh.is_valid(order[i].t)) level_region(mesh, order[i].t, region);
      int l = 0;
      for (Id v : region) {
        if (std::size_t(v) >= last.size()) last.resize(std::size_t(v) + 1, 0);
        l = std::max(l, last[v]);
      }
      ++l;
      for (Id v : region) last[v] = l;
      level[i] = l;
      levels = std::max(levels, l);
    }
    // Entries grouped by level, each group in the serial order.
    std::vector<std::size_t> start(std::size_t(levels) + 2, 0);
    for (int l : level) ++start[std::size_t(l) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<std::size_t> slot(order.size()), fill(start.begin(), start.end());
    for (std::size_t i = 0; i < order.size(); ++i) slot[fill[std::size_t(level[i])]++] = i;
    PassStats total;
    total.threads = threads;
    total.levels = std::size_t(levels);
    std::vector<PassStats> per(static_cast<std::size_t>(threads));
    auto run_entry = [&](const Entry& e, PassStats& st) {
      if (!mesh.is_valid(e.t)) {
        ++st.stale_tuple;
        return;
      }
      ++st.attempted;
      if ((*fns[e.op])(mesh, e.t)) {
        ++st.succeeded;
        return;
      }
      count_rejection(st, mesh.last_rejection());
    };
    tbb::task_arena arena(threads);
    for (int l = 1; l <= levels; ++l) {
      const std::size_t lo = start[std::size_t(l)], hi = start[std::size_t(l) + 1];
      if (reverse_levels || hi - lo < 2) {  // a test's order, or not worth the hand-off
        ThreadSlotScope slot0(0);
        for (std::size_t k = lo; k < hi; ++k)
          run_entry(order[slot[reverse_levels ? lo + hi - 1 - k : k]], per[0]);
        continue;
      }
      std::atomic<std::size_t> next{lo};
      run_in_slots(arena, threads, [&](int p) {
        for (std::size_t j = next.fetch_add(1); j < hi; j = next.fetch_add(1))
          run_entry(order[slot[j]], per[std::size_t(p)]);
      });
    }
    for (const PassStats& s : per) add(total, s);
    total.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return total;
  }
  for (std::size_t i = 0; i < work.size(); ++i) {
    const Tuple& t = work[i].second;
    const int p = threads > 1 && t.vid < part.size() ? part[t.vid] : 0;
    queues[p].push(Entry{priorities[i], ops[i], t, 0});
  }

  std::atomic<bool> stop{false};
  std::mutex tail_mutex;
  std::vector<Entry> tail;
  auto default_lock = [&](const Tuple& t) {
    const auto seeds = mesh.lock_seeds(t);
    return mesh.try_lock_region(std::span<const Id>(seeds.data(), seeds.size()), lock_rings);
  };
  constexpr double k_all = -std::numeric_limits<double>::infinity();

  // Runs the entries of q whose priority is at least `threshold`.
  auto process = [&](Queue& q, PassStats& st, bool locking, double threshold) {
    std::vector<Entry> deferred;
    while (!stop.load(std::memory_order_relaxed)) {
      if (q.empty() || q.top().priority < threshold) {
        if (deferred.empty()) break;
        for (Entry& e : deferred) {
          if (++e.retries >= max_retry_limit) {
            std::lock_guard<std::mutex> guard(tail_mutex);
            tail.push_back(e);
            ++st.serial_tail;
          } else {
            q.push(e);
          }
        }
        deferred.clear();
        continue;
      }
      const Entry e = q.top();
      q.pop();
      if (!mesh.is_valid(e.t)) {
        ++st.stale_tuple;
        continue;
      }
      const Work w{names[e.op], e.t};
      if (locking) {
        const bool ok = lock_vertices ? lock_vertices(mesh, w) : default_lock(e.t);
        if (!ok) {
          mesh.release_vertex_locks();
          ++st.lock_failures;
          deferred.push_back(e);
          continue;
        }
        if (!mesh.is_valid(e.t)) {  // changed between the first check and the locks
          mesh.release_vertex_locks();
          ++st.stale_tuple;
          continue;
        }
      }
      if (should_process && !should_process(mesh, w, e.priority)) {
        if (locking) mesh.release_vertex_locks();
        ++st.stale_priority;
        continue;
      }
      ++st.attempted;
      const std::optional<Tuple> result = (*fns[e.op])(mesh, e.t);
      if (result) {
        ++st.succeeded;
        if (renew_neighbor_tuples)
          for (const auto& [name, t] : renew_neighbor_tuples(mesh, names[e.op], *result)) {
            const int op = op_index(name);
            q.push(Entry{prio(op, t), op, t, 0});
          }
        if (stopping_criterion && stopping_criterion(mesh)) stop.store(true);
      } else {
        count_rejection(st, mesh.last_rejection());
      }
      if (locking) mesh.release_vertex_locks();
    }
  };

  // Epoch threshold: the priority above which about `epoch_fraction` of all queued entries lie,
  // estimated from an evenly strided sample of every queue.
  auto epoch_threshold = [&]() {
    std::size_t total = 0;
    for (const Queue& q : queues) total += q.size();
    if (epoch_fraction <= 0 || total < 64) return k_all;
    std::vector<double> sample;
    for (const Queue& q : queues) {
      const std::size_t n = std::min<std::size_t>(q.size(), 1024);
      for (std::size_t i = 0; i < n; ++i) sample.push_back(q.heap[i * q.size() / n].priority);
    }
    const std::size_t k =
        std::min(sample.size() - 1, std::size_t(epoch_fraction * double(sample.size())));
    std::nth_element(sample.begin(), sample.begin() + std::ptrdiff_t(k), sample.end(),
                     std::greater<double>());
    return sample[k];
  };

  PassStats total;
  total.threads = threads;
  if (threads == 1) {
    ThreadSlotScope slot(0);
    process(queues[0], total, false, k_all);
  } else {
    std::vector<PassStats> per(threads);
    tbb::task_arena arena(threads);
    for (;;) {
      bool any = false;
      for (const Queue& q : queues) any = any || !q.empty();
      if (!any || stop.load()) break;
      const double threshold = epoch_threshold();
      ++total.epochs;
      run_in_slots(arena, threads, [&](int p) { process(queues[p], per[p], true, threshold); });
      if (!stop.load() && !tail.empty()) {
        // The serial tail of this epoch: same threshold; what it renews below the threshold
        // goes back to the partition queues for the next epochs.
        Queue q;
        for (const Entry& e : tail) q.push(Entry{e.priority, e.op, e.t, 0});
        tail.clear();
        ThreadSlotScope slot(0);
        process(q, total, false, threshold);
        for (const Entry& e : q.heap) {
          const std::size_t p = e.t.vid < part.size() ? std::size_t(part[e.t.vid]) : 0;
          queues[p].push(e);
        }
      }
    }
    for (const PassStats& s : per) add(total, s);
  }
  total.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return total;
}

template class ExecutePass<TriMesh>;
template class ExecutePass<TetMesh>;

}  // namespace curvefem::meshing::editing
