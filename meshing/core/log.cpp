#include "meshing/core/log.hpp"

#include <atomic>
#include <cstdio>
#include <mutex>

#include "meshing/core/error.hpp"

namespace curvefem::log {
namespace {
std::atomic<Level> g_level{Level::info};
std::mutex g_mutex;
Sink g_sink;

void default_sink(Level level, std::string_view message) {
  const char* prefix = level == Level::warn ? "warning: " : level == Level::error ? "error: " : "";
  std::fprintf(stderr, "%s%.*s\n", prefix, static_cast<int>(message.size()), message.data());
}
}  // namespace

void set_level(Level level) { g_level = level; }
Level level() { return g_level; }
bool enabled(Level l) { return l >= g_level.load() && l != Level::off; }

Level parse_level(std::string_view name) {
  if (name == "trace") return Level::trace;
  if (name == "debug") return Level::debug;
  if (name == "info") return Level::info;
  if (name == "warn" || name == "warning") return Level::warn;
  if (name == "error") return Level::error;
  if (name == "off") return Level::off;
  throw InputError("unknown log level '" + std::string(name) +
                   "' (expected trace, debug, info, warn, error or off)");
}

void set_sink(Sink sink) {
  std::lock_guard lock(g_mutex);
  g_sink = std::move(sink);
}

void write(Level level, std::string_view message) {
  std::lock_guard lock(g_mutex);
  if (g_sink)
    g_sink(level, message);
  else
    default_sink(level, message);
}

}  // namespace curvefem::log
