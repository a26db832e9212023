#pragma once
// The editing engine's notion of "which worker am I": a small integer in [0, k_max_threads)
// set by the scheduler for each of its tasks (0 outside the scheduler). Per-thread journals,
// undo logs and lock ownership are indexed by it, so no thread-local storage leaks into the API.

namespace curvefem::meshing::editing {

inline constexpr int k_max_threads = 64;

int current_thread_slot();

// Sets the current slot for the lifetime of the scope and restores the previous one.
class ThreadSlotScope {
 public:
  explicit ThreadSlotScope(int slot);
  ~ThreadSlotScope();
  ThreadSlotScope(const ThreadSlotScope&) = delete;
  ThreadSlotScope& operator=(const ThreadSlotScope&) = delete;

 private:
  int m_previous;
};

// Per-slot scratch storage for user hooks (e.g. values cached in `before` for `after`).
template <class T>
class PerThread {
 public:
  T& local() { return m_values[current_thread_slot()]; }
  const T& local() const { return m_values[current_thread_slot()]; }

 private:
  T m_values[k_max_threads]{};
};

}  // namespace curvefem::meshing::editing
