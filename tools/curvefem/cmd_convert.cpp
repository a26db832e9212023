// `curvefem convert INPUT OUTPUT`: converts triangle surfaces between OBJ, OFF, STL, PLY, MSH and
// VTU (face tags kept where the format holds them), and Lagrange volume meshes between MSH and
// VTU (order 1..4). The formats come from the extensions.
#include <algorithm>
#include <cctype>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/io/msh_io.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {
namespace {

struct ConvertOptions {
  GlobalOptions global;
  std::string input, output;
  bool ascii = false;
  bool msh22 = false;
};

std::string extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

int run_convert(const ConvertOptions& o) {
  auto progress = apply_global_options(o.global);
  const std::string in = extension(o.input), out = extension(o.output);
  const bool out_volume_format = out == ".vtu" || out == ".msh";
  // Volume meshes: VTU in, or MSH in with tetrahedra.
  bool volume = in == ".vtu";
  LagrangeMesh mesh;
  if (in == ".vtu") {
    mesh = io::read_vtu(o.input).mesh;
  } else if (in == ".msh") {
    mesh = io::read_msh(o.input);
    volume = mesh.kind == CellKind::tetrahedron || mesh.order > 1;
  }
  if (volume) {
    if (!out_volume_format)
      throw InputError("a volume or high-order mesh converts only to .vtu or .msh",
                       {.file = o.output});
    if (out == ".vtu")
      io::write_vtu(o.output, mesh);
    else
      io::write_msh(o.output, mesh);
    log::info("wrote ", mesh.num_cells(), " cells of order ", mesh.order, " to ", o.output);
    return 0;
  }
  const SurfaceMesh surface = io::read_surface(o.input);
  if (out == ".vtu") {
    io::write_vtu(o.output, as_triangle_mesh(surface));
  } else {
    io::SurfaceFormat format = io::surface_format_from_extension(o.output);
    if (o.ascii && format == io::SurfaceFormat::stl_binary) format = io::SurfaceFormat::stl_ascii;
    if (o.ascii && format == io::SurfaceFormat::ply_binary) format = io::SurfaceFormat::ply_ascii;
    if (o.msh22 && format == io::SurfaceFormat::msh41) format = io::SurfaceFormat::msh22;
    io::write_surface(o.output, surface, format);
  }
  log::info("wrote ", surface.num_faces(), " faces to ", o.output);
  return 0;
}

}  // namespace

void register_convert(CLI::App& app) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* sub = app.add_subcommand(
      "convert", "convert surfaces (obj off stl ply msh vtu) and volume meshes (msh vtu)");
  sub->add_option("input", options->input, "input mesh")->required()->check(CLI::ExistingFile);
  sub->add_option("output", options->output, "output mesh (format from the extension)")->required();
  sub->add_flag("--ascii", options->ascii, "write STL / PLY as text instead of binary");
  sub->add_flag("--msh22", options->msh22, "write MSH 2.2 instead of 4.1 (surfaces)");
  add_global_options(*sub, options->global);
  add_command(sub, [options] { return run_convert(*options); });
}

}  // namespace curvefem::cli
