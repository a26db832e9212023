#include "pipeline/gnuplot_plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

extern char** environ;

namespace curvefem::pipeline {
namespace {

/// A single-quoted gnuplot string ('' stands for one quote; no other escapes in single quotes).
std::string quoted(const std::string& text) {
  std::string out = "'";
  for (const char c : text) {
    if (c == '\'') out += '\'';
    if (c == '\n' || c == '\r') {
      out += ' ';
      continue;
    }
    out += c;
  }
  return out + "'";
}

}  // namespace

std::string gnuplot_script(const LogLogPlot& plot) {
  std::ostringstream s;
  s.precision(17);
  s << "# written by curvefem; re-plot by running gnuplot on this file in its folder\n";
  s << "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
    << "  set terminal pngcairo size 1200,800 noenhanced font ',11'\n"
    << "} else {\n"
    << "  set terminal png size 1200,800 noenhanced\n"
    << "}\n";
  s << "set output " << quoted(plot.output) << "\n";
  s << "set title " << quoted(plot.title) << "\n";
  s << "set xlabel " << quoted(plot.xlabel) << "\n";
  s << "set ylabel " << quoted(plot.ylabel) << "\n";
  s << "set logscale xy\nset format y '%.0e'\nset grid xtics ytics mxtics mytics\n";
  s << "set key outside right top box\n";
  int drawn = 0;
  for (std::size_t c = 0; c < plot.curves.size(); ++c) {
    const PlotCurve& curve = plot.curves[c];
    s << "$curve" << c << " << EOD\n";
    for (std::size_t i = 0; i < curve.x.size() && i < curve.y.size(); ++i)
      if (curve.x[i] > 0 && curve.y[i] > 0 && std::isfinite(curve.x[i]) &&
          std::isfinite(curve.y[i]))
        s << curve.x[i] << ' ' << curve.y[i] << '\n';
    s << "EOD\n";
  }
  s << "plot";
  for (std::size_t c = 0; c < plot.curves.size(); ++c) {
    const PlotCurve& curve = plot.curves[c];
    if (c > 0) s << ", \\\n    ";
    s << " $curve" << c << " using 1:2 with linespoints lc " << curve.color << " dt " << curve.dash
      << " pt " << curve.point_type << " ps 1.3 lw 2 title " << quoted(curve.title);
    ++drawn;
  }
  if (drawn == 0) s << " 1/0 notitle";  // an empty frame
  s << "\nunset output\n";
  return s.str();
}

std::string run_gnuplot(const std::filesystem::path& dir, const std::string& script_name) {
  const std::filesystem::path log = dir / (".gnuplot-" + std::to_string(getpid()) + ".log");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addchdir_np(&actions, dir.c_str());
  std::string program = "gnuplot", script = script_name;
  char* argv[] = {program.data(), script.data(), nullptr};
  pid_t pid = -1;
  const int spawned = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  std::error_code ec;
  if (spawned != 0) {
    std::filesystem::remove(log, ec);
    if (spawned == ENOENT) return "gnuplot not found (Debian package gnuplot-nox)";
    return std::string("cannot start gnuplot: ") + std::strerror(spawned);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return std::string("waitpid: ") + std::strerror(errno);
  std::string messages;
  {
    std::ifstream in(log);
    std::ostringstream text;
    text << in.rdbuf();
    messages = text.str();
  }
  std::filesystem::remove(log, ec);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return {};
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
    return "gnuplot not found (Debian package gnuplot-nox)";
  while (!messages.empty() && (messages.back() == '\n' || messages.back() == ' '))
    messages.pop_back();
  return "gnuplot failed (" +
         (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                            : std::string("killed by a signal")) +
         ")" + (messages.empty() ? "" : ": " + messages);
}

}  // namespace curvefem::pipeline
