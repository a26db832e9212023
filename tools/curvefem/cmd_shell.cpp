// `curvefem shell INPUT -o DIR [--thickness R] [--no-simplify] [--threads N]`: builds the
// prismatic shell of a closed surface (meshing/shell), verifies it with independent code and
// writes shell.vtu (prisms as VTK_WEDGE, cell data `half`: 0 base→mid, 1 mid→top, `input_face`),
// middle.obj and report.json. Without --no-simplify the shell is coarsened by collapses that
// keep it positive, a section of the input and separated from it (meshing/shell/simplify.hpp).
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {
namespace {

namespace sh = meshing::shell;

struct ShellArgs {
  std::string input, output;
  double thickness = 0.02;
  bool no_simplify = false;
  GlobalOptions global;
};

// VTU (ascii) with one VTK_WEDGE (13) per half-prism; VTK's wedge lists the bottom triangle then
// the top one, both counter-clockwise seen from the same side, which our (base, mid, top) order is.
void write_wedges(const std::filesystem::path& path, const sh::Shell& s) {
  const int nv = int(s.mid.rows()), nf = int(s.F.rows());
  std::ostringstream out;
  out.precision(17);
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
         "byte_order=\"LittleEndian\">\n"
      << "<UnstructuredGrid><Piece NumberOfPoints=\"" << 3 * nv << "\" NumberOfCells=\"" << 2 * nf
      << "\">\n"
      << "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const Eigen::MatrixXd* M : {&s.base, &s.mid, &s.top})
    for (int v = 0; v < nv; ++v)
      out << (*M)(v, 0) << ' ' << (*M)(v, 1) << ' ' << (*M)(v, 2) << '\n';
  out << "</DataArray></Points>\n<Cells><DataArray type=\"Int64\" Name=\"connectivity\" "
         "format=\"ascii\">\n";
  for (int half = 0; half < 2; ++half)
    for (int f = 0; f < nf; ++f) {
      for (int k = 0; k < 3; ++k) out << half * nv + s.F(f, k) << ' ';
      for (int k = 0; k < 3; ++k) out << (half + 1) * nv + s.F(f, k) << ' ';
      out << '\n';
    }
  out << "</DataArray><DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (int c = 1; c <= 2 * nf; ++c) out << 6 * c << '\n';
  out << "</DataArray><DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (int c = 0; c < 2 * nf; ++c) out << "13\n";
  out << "</DataArray></Cells>\n<CellData><DataArray type=\"Int32\" Name=\"half\" "
         "format=\"ascii\">\n";
  for (int half = 0; half < 2; ++half)
    for (int f = 0; f < nf; ++f) out << half << '\n';
  out << "</DataArray><DataArray type=\"Int32\" Name=\"input_face\" format=\"ascii\">\n";
  for (int half = 0; half < 2; ++half)
    for (int f = 0; f < nf; ++f) out << s.face_parent[f] << '\n';
  out << "</DataArray></CellData>\n</Piece></UnstructuredGrid></VTKFile>\n";
  write_text_file_atomic(path, out.str());
}

}  // namespace

void register_shell(CLI::App& app) {
  auto args = std::make_shared<ShellArgs>();
  CLI::App* sub = app.add_subcommand(
      "shell", "build and verify the bijective prismatic shell of a closed surface");
  sub->add_option("input", args->input, "closed, oriented surface (.obj .off .stl .ply .msh)")
      ->required();
  sub->add_option("-o,--output", args->output, "output folder")->required();
  sub->add_option("--thickness", args->thickness,
                  "cap on each half-pillar, relative to the longest bbox edge")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--no-simplify", args->no_simplify, "keep the input as the middle surface");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    auto progress = apply_global_options(args->global);
    Stopwatch total;
    const SurfaceMesh input = io::read_surface(args->input);
    sh::ShellOptions options;
    options.max_thickness_rel = args->thickness;
    options.threads = args->global.threads;
    sh::ShellStats stats;
    sh::Shell shell = sh::build_shell(input, options, stats, progress->callback());
    sh::SimplifyStats simplify;
    if (!args->no_simplify) {
      sh::SimplifyOptions so;
      so.threads = args->global.threads > 0 ? args->global.threads : 2;
      shell = sh::simplify_shell(shell, input, so, simplify);
      stats.stage_seconds.emplace_back("simplify", simplify.seconds);
    }
    const sh::ShellVerification check = sh::verify_shell(shell, input);

    StagedOutputDir out(args->output);
    write_wedges(out.path("shell.vtu"), shell);
    SurfaceMesh middle;
    middle.V = shell.mid;
    middle.F = shell.F;
    io::write_surface(out.path("middle.obj"), middle, io::SurfaceFormat::obj);
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();
    for (const auto& [name, s] : stats.stage_seconds) stages[name] = s;
    stages["verification"] = check.seconds;
    nlohmann::ordered_json report = {
        {"input", args->input},
        {"input_faces", stats.input_faces},
        {"input_vertices", stats.input_vertices},
        {"prisms", int(shell.F.rows())},
        {"simplified", !args->no_simplify},
        {"prisms_per_input_face", double(shell.F.rows()) / double(stats.input_faces)},
        {"simplify_collapses",
         [&] {
           int n = 0;
           for (const auto& p : simplify.passes) n += int(p.succeeded);
           return n;
         }()},
        {"singular_vertices", stats.singular_vertices},
        {"pinch_splits", stats.pinch_splits},
        {"beveled_faces", nullptr},
        {"beveling", "not implemented"},
        {"min_thickness_rel", stats.min_thickness_rel},
        {"median_thickness_rel", stats.median_thickness_rel},
        {"max_thickness_rel", stats.max_thickness_rel},
        {"positive_verified", check.positive()},
        {"non_positive_prisms", check.non_positive_faces},
        {"intersection_free_verified", check.separated()},
        {"input_faces_intersecting_shell", check.intersecting_input_faces},
        {"is_section_verified", check.section()},
        {"non_section_prisms", check.non_section_faces},
        {"roundtrip_max_error_rel", check.roundtrip_max_error_rel},
        {"roundtrip_failures", check.roundtrip_failures},
        {"time_s", stages},
        {"peak_rss_mb", peak_rss_mb()}};
    report["time_s"]["total"] = total.seconds();
    write_text_file_atomic(out.path("report.json"), report.dump(2) + "\n");
    out.commit();
    progress.reset();
    std::printf(
        "shell: %d prisms, %d singular, thickness median %.3g (min %.3g) of bbox; positive %s, "
        "intersection-free %s, section %s (%d prisms fail), roundtrip %.2g; %.2f s; %s\n",
        int(shell.F.rows()), stats.singular_vertices, stats.median_thickness_rel,
        stats.min_thickness_rel, check.positive() ? "yes" : "NO", check.separated() ? "yes" : "NO",
        check.section() ? "yes" : "NO", check.non_section_faces, check.roundtrip_max_error_rel,
        total.seconds(), out.final_path("report.json").string().c_str());
    std::fflush(stdout);
    return check.positive() && check.separated() ? 0 : 3;
  });
}

}  // namespace curvefem::cli
