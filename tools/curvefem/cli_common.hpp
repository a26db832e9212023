// Shared plumbing of the curvefem subcommands: global options, logging/progress set-up, and the
// one place where exceptions become an error line and an exit code (DESIGN.md §3).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <string>

#include "meshing/core/progress.hpp"

namespace curvefem::cli {

/// Options every subcommand accepts.
struct GlobalOptions {
  bool quiet = false;
  std::string log_level = "info";
  int threads = 0;  ///< 0 = all cores
};

/// Adds --quiet, --log-level, --threads to `app` (bound to `options`).
void add_global_options(CLI::App& app, GlobalOptions& options);

/// Applies logging level (and thread count for later oneTBB work); returns the progress renderer.
std::unique_ptr<TerminalProgress> apply_global_options(const GlobalOptions& options);

/// Runs `body`, mapping curvefem errors to their exit codes with one line on stderr.
int guarded(const std::function<int()>& body);

}  // namespace curvefem::cli
