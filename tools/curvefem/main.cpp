// curvefem command-line tool. Exit codes (DESIGN.md §3): 0 success, 1 usage error, 2 invalid
// input, 3 algorithm could not meet its guarantees, 4 I/O failure.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>

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
  // Distributed runs are not implemented: under `mpirun -n N`, N > 1, every rank would run the
  // whole command and write the same files. Refuse on every rank, before any output exists.
  if (const int ranks = mpi_launch_size(); ranks > 1) {
    std::fprintf(stderr,
                 "curvefem: error: started as %d MPI processes; distributed runs are not "
                 "implemented yet (meshing, assembly and solve run in one process, with threads: "
                 "--threads N). Run without mpirun, or with -n 1\n",
                 ranks);
    return 2;
  }
  return curvefem::cli::run_selected(app);
}
