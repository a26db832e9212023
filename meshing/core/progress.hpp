// Progress reporting for long loops.
//
// Library code receives a `ProgressFn` (possibly empty) and reports (stage, fraction in [0,1]).
// `ProgressTicker` throttles calls from a hot loop. `TerminalProgress` is the CLI's renderer:
// on a TTY a one-line bar "stage [=====>    ]  42%  ETA 3 s" on stderr, otherwise one line per
// stage when the stage finishes, nothing at all when quiet.
#pragma once

#include <cstddef>
#include <cstdio>
#include <functional>
#include <string>
#include <string_view>
#include <utility>

#include "meshing/core/timer.hpp"

namespace curvefem {

using ProgressFn = std::function<void(std::string_view stage, double fraction)>;

/// Calls `fn(stage, i / n)` at most every ~1% and once at the end. Cheap when fn is empty.
class ProgressTicker {
 public:
  ProgressTicker(const ProgressFn& fn, std::string stage, std::size_t total);
  void tick(std::size_t done);
  void finish();

 private:
  const ProgressFn& m_fn;
  std::string m_stage;
  std::size_t m_total;
  std::size_t m_next;
};

enum class ProgressMode { quiet, lines, bar };

class TerminalProgress {
 public:
  /// `automatic`: bar if stderr is a terminal and $CI is unset, lines otherwise.
  static ProgressMode automatic_mode(bool quiet);
  explicit TerminalProgress(ProgressMode mode, std::FILE* out = stderr);
  ~TerminalProgress();
  void update(std::string_view stage, double fraction);
  /// Ends the current stage (prints its line in `lines` mode, finishes the bar in `bar` mode).
  void end_stage();
  ProgressFn callback();
  /// Text drawn before the stage name, e.g. "[3/6] p=2  " for one run of many.
  void set_prefix(std::string prefix) { m_prefix = std::move(prefix); }
  /// Bar mode: a finished stage is erased instead of leaving a "done" line (a bar nested in an
  /// outer display that prints its own lines).
  void set_transient(bool transient) { m_transient = transient; }

 private:
  ProgressMode m_mode;
  std::FILE* m_out;
  std::string m_prefix;
  bool m_transient = false;
  std::string m_stage;
  Stopwatch m_stage_watch;
  double m_last_draw = -1.0;
  double m_fraction = 0.0;
};

}  // namespace curvefem
