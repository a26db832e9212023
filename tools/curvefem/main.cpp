// curvefem command-line tool. Exit codes (DESIGN.md §3): 0 success, 1 usage error, 2 invalid
// input, 3 algorithm could not meet its guarantees, 4 I/O failure.
#include <CLI/CLI.hpp>

#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

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
  return curvefem::cli::run_selected(app);
}
