// curvefem command-line tool. Exit codes (DESIGN.md §3): 0 success, 1 usage error, 2 invalid
// input, 3 algorithm could not meet its guarantees, 4 I/O failure.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "fem/solvers/distributed.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace {

// The number of processes an MPI launcher started (mpirun / mpiexec of OpenMPI or MPICH); 1 when
// not launched by one.
int mpi_launch_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* v = std::getenv(name)) return std::max(1, std::atoi(v));
  return 1;
}

/// `run` under a launcher with several processes (fem/solvers/distributed.hpp): rank 0 runs the
/// command, whose linear solves are spread over every rank; the other ranks only serve those
/// solves (no output, no progress).
int run_distributed(CLI::App& app) {
  int rank = -1;
  if (const int failed = curvefem::cli::guarded([&] {
        rank = curvefem::fem::distributed::start();
        return 0;
      }))
    return failed;
  int code = 0;
  if (rank == 0) {
    code = curvefem::cli::run_selected(app);
    curvefem::fem::distributed::release_workers();
  } else {
    curvefem::fem::distributed::serve();
  }
  curvefem::fem::distributed::finish();
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "curvefem: coarse, curved, certified tetrahedral meshes and p-FEM from dense triangle "
      "surfaces"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "curvefem 0.1.0");
  curvefem::cli::register_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 1;  // usage error
  }
  // Under `mpirun -n N`, N > 1, only `run` is distributed (its linear solves); any other command
  // would run N times and write the same files: refuse it on every rank, before any output.
  if (const int ranks = mpi_launch_size(); ranks > 1) {
    if (!app.got_subcommand("run")) {
      std::fprintf(stderr,
                   "curvefem: error: started as %d MPI processes; only `curvefem run` runs "
                   "distributed (its linear solves over the ranks). Run this command without "
                   "mpirun, or with -n 1 (threads: --threads N)\n",
                   ranks);
      return 2;
    }
    return run_distributed(app);
  }
  return curvefem::cli::run_selected(app);
}
