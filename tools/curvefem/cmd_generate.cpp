// `curvefem generate NAME -o OUT` writes a procedural adversarial surface (meshing/core/
// adversarial.hpp); `curvefem generate --list` prints the names with what each stresses.
#include <cstdio>
#include <memory>
#include <string>

#include "meshing/core/adversarial.hpp"
#include "meshing/core/error.hpp"
#include "meshing/io/surface_io.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {

void register_generate(CLI::App& app) {
  struct Args {
    std::string name, output;
    bool list = false;
    GlobalOptions global;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "generate", "write a procedural adversarial surface (exit 2 for an unknown name)");
  sub->add_option("name", args->name, "surface name (see --list)");
  sub->add_option("-o,--output", args->output, "output surface (.obj .off .stl .ply .msh)");
  sub->add_flag("--list", args->list, "print the names and what each stresses");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    apply_global_options(args->global);
    if (args->list) {
      for (const auto& s : adversarial_surfaces())
        std::printf("%-28s %s\n", s.name.c_str(), s.what.c_str());
      return 0;
    }
    if (args->name.empty() || args->output.empty())
      throw InputError("generate: give a NAME and -o OUTPUT (or --list)");
    const SurfaceMesh mesh = make_adversarial(args->name);
    io::write_surface(args->output, mesh, io::surface_format_from_extension(args->output));
    return 0;
  });
}

}  // namespace curvefem::cli
