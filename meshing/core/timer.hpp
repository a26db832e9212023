// Wall-clock timers: a stopwatch, a scoped timer that adds its lifetime to a named stage, and an
// ordered stage → seconds table that reports write as `time_s`.
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace curvefem {

class Stopwatch {
 public:
  Stopwatch() : m_start(std::chrono::steady_clock::now()) {}
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
  }
  void reset() { m_start = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point m_start;
};

/// Stage timings in insertion order; adding to an existing stage accumulates.
class Timings {
 public:
  void add(const std::string& stage, double seconds);
  double get(const std::string& stage) const;  ///< 0 when absent
  double total() const;
  const std::vector<std::pair<std::string, double>>& stages() const { return m_stages; }

 private:
  std::vector<std::pair<std::string, double>> m_stages;
};

/// Adds the time between construction and destruction to `timings[stage]`.
class ScopedTimer {
 public:
  ScopedTimer(Timings& timings, std::string stage)
      : m_timings(timings), m_stage(std::move(stage)) {}
  ~ScopedTimer() { m_timings.add(m_stage, m_watch.seconds()); }
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;

 private:
  Timings& m_timings;
  std::string m_stage;
  Stopwatch m_watch;
};

/// Peak resident set size of this process in MiB (from /proc/self/status; 0 if unavailable).
double peak_rss_mb();

}  // namespace curvefem
