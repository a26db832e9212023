// `curvefem check INPUT [--json]`: validity of a triangle surface for meshing (DESIGN.md §3).
// Prints a summary block and one line per defect (or one JSON object with --json) on stdout.
// Exit 0 when the surface is acceptable, 2 when it is not or cannot be read as triangles.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "meshing/check/check_surface.hpp"
#include "meshing/io/surface_io.hpp"
#include "pipeline/report_json.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {
namespace {

struct CheckArgs {
  std::string input;
  bool json = false;
  bool skip_self_intersections = false;
  GlobalOptions global;
};

const char* yes_no(bool b) { return b ? "yes" : "no"; }

void print_human(const std::string& input, const check::CheckReport& r) {
  auto row = [](const char* label, const std::string& value) {
    std::printf("%-24s %s\n", label, value.c_str());
  };
  auto num = [](long long n) { return std::to_string(n); };
  auto with = [](bool flag, long long n, const char* what) {
    return std::string(flag ? "yes" : "no") + " (" + std::to_string(n) + " " + what + ")";
  };
  char buf[128];
  row("input", input);
  row("vertices", num(r.vertices) + " (" + num(r.unreferenced_vertices) + " unreferenced)");
  row("faces", num(r.faces));
  row("components", num(r.components));
  row("closed", with(r.closed, r.boundary_edges, "boundary edges"));
  row("edge-manifold", with(r.edge_manifold, r.non_manifold_edges, "non-manifold edges"));
  row("vertex-manifold", with(r.vertex_manifold, r.non_manifold_vertices, "non-manifold vertices"));
  row("oriented", with(r.consistently_oriented, r.inconsistent_edges, "inconsistent edges"));
  std::snprintf(buf, sizeof buf, " (signed volume %.6g)", r.signed_volume);
  row("orientation", std::string(r.orientation_sign > 0   ? "outward"
                                 : r.orientation_sign < 0 ? "inward"
                                                          : "undefined") +
                         buf);
  row("genus", r.genus >= 0 ? num(r.genus) : std::string("undefined (not a closed manifold)"));
  row("degenerate faces", num(r.degenerate_faces));
  std::snprintf(buf, sizeof buf, "%.4g deg (max %.4g deg)", r.min_angle_deg, r.max_angle_deg);
  row("min angle", buf);
  row("duplicate vertices", num(r.duplicate_vertices));
  row("duplicate faces", num(r.duplicate_faces));
  row("self-intersecting pairs",
      r.self_intersections_checked ? num(r.self_intersecting_pairs) : std::string("not checked"));
  row("volume bounded", yes_no(r.volume_bounded));
  std::snprintf(buf, sizeof buf, "%.3f s", r.time_s);
  row("check time", buf);
  for (const check::Defect& d : r.defects)
    std::printf("%s: %s\n", d.kind.c_str(), d.message.c_str());
  for (const check::Defect& w : r.warnings)
    std::printf("warning: %s: %s\n", w.kind.c_str(), w.message.c_str());
  std::printf("acceptable for meshing: %s\n", yes_no(r.acceptable));
  // What a user can still do with a closed, oriented surface whose only defect is that it
  // passes through itself.
  if (r.defects.size() == 1 && r.defects.front().kind == "self_intersection")
    std::printf(
        "what works: `curvefem shell IN -o DIR --allow-self-intersections` (a locally injective "
        "shell, for remeshing and attribute transfer); `curvefem deform IN -o OUT.obj --untangle` "
        "(genus 0: "
        "a flow that removes the self-intersections)\n");
}

}  // namespace

void register_check(CLI::App& app) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* sub = app.add_subcommand(
      "check", "validate a triangle surface for meshing (exit 0 acceptable, 2 not acceptable)");
  sub->add_option("input", args->input, "surface file (.obj .off .stl .ply .msh)")->required();
  sub->add_flag("--json", args->json, "print the report as one JSON object on stdout");
  sub->add_flag("--no-self-intersections", args->skip_self_intersections,
                "skip the self-intersection test (reported as not checked)");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    auto progress = apply_global_options(args->global);
    const SurfaceMesh mesh = io::read_surface(args->input);
    check::CheckOptions options;
    options.self_intersections = !args->skip_self_intersections;
    const check::CheckReport report = check::check_surface(mesh, options, progress->callback());
    progress.reset();  // finish the progress line on stderr before the report on stdout
    if (args->json) {
      nlohmann::json j = pipeline::check_report_json(report);
      j["input"] = args->input;
      std::printf("%s\n", j.dump(2).c_str());
    } else
      print_human(args->input, report);
    std::fflush(stdout);
    return report.acceptable ? 0 : 2;
  });
}

}  // namespace curvefem::cli
