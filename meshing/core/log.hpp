// Logging facade. Library code logs through here and never writes to stdout.
//
// Messages go to a sink (default: stderr, one line each, prefixed by the level for warnings and
// errors). The CLI sets the level from --log-level / --quiet and may install its own sink (e.g. to
// interleave with a progress bar). Thread-safe: the sink is called under a mutex.
#pragma once

#include <functional>
#include <sstream>
#include <string>
#include <string_view>

namespace curvefem::log {

enum class Level { trace = 0, debug = 1, info = 2, warn = 3, error = 4, off = 5 };

using Sink = std::function<void(Level, std::string_view)>;

void set_level(Level level);
Level level();
/// Parses "trace|debug|info|warn|error|off"; throws InputError otherwise.
Level parse_level(std::string_view name);
/// Replaces the sink; an empty function restores the default (stderr).
void set_sink(Sink sink);
bool enabled(Level level);
void write(Level level, std::string_view message);

/// Streams all arguments into one string: log::cat("faces ", n, " in ", t, " s").
template <class... Args>
std::string cat(const Args&... args) {
  std::ostringstream s;
  (s << ... << args);
  return s.str();
}

template <class... Args>
void trace(const Args&... args) {
  if (enabled(Level::trace)) write(Level::trace, cat(args...));
}
template <class... Args>
void debug(const Args&... args) {
  if (enabled(Level::debug)) write(Level::debug, cat(args...));
}
template <class... Args>
void info(const Args&... args) {
  if (enabled(Level::info)) write(Level::info, cat(args...));
}
template <class... Args>
void warn(const Args&... args) {
  if (enabled(Level::warn)) write(Level::warn, cat(args...));
}
template <class... Args>
void error(const Args&... args) {
  if (enabled(Level::error)) write(Level::error, cat(args...));
}

}  // namespace curvefem::log
