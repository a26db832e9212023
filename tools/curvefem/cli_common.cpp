#include "tools/curvefem/cli_common.hpp"

#include <tbb/global_control.h>

#include <cstdio>
#include <exception>
#include <new>

#include "fem/solvers/linear_solver.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"

namespace curvefem::cli {

void add_global_options(CLI::App& app, GlobalOptions& options) {
  app.add_flag("-q,--quiet", options.quiet, "print nothing but errors and requested output");
  app.add_option("--log-level", options.log_level, "trace|debug|info|warn|error|off")
      ->capture_default_str();
  app.add_option("--threads", options.threads, "worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
}

std::unique_ptr<TerminalProgress> apply_global_options(const GlobalOptions& options) {
  log::set_level(options.quiet ? log::Level::warn : log::parse_level(options.log_level));
  // oneTBB (assembly, CGAL's parallel checks) uses at most --threads workers for the whole run.
  static std::unique_ptr<tbb::global_control> limit;
  // The BLAS under CHOLMOD and PETSc gets the same count (all cores when --threads is 0).
  if (options.threads > 0) {
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  static_cast<std::size_t>(options.threads));
    fem::set_blas_threads(options.threads);
  }
  return std::make_unique<TerminalProgress>(TerminalProgress::automatic_mode(options.quiet));
}

int guarded(const std::function<int()>& body) {
  try {
    return body();
  } catch (const Error& e) {
    std::fprintf(stderr, "curvefem: error: %s\n", e.what());
    return e.exit_code();
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "curvefem: error: out of memory\n");
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "curvefem: internal error: %s\n", e.what());
    return 3;
  }
}

}  // namespace curvefem::cli
