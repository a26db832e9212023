// `curvefem check INPUT [--json]`: validity of a triangle surface for meshing (DESIGN.md §3).
// Prints a summary block and one line per defect (or one JSON object with --json) on stdout.
// Exit 0 when the surface is acceptable, 2 when it is not or cannot be read as triangles.
// With `--merge-short-edges L -o OUT`, the edges shorter than L × the bbox's longest edge are
// merged (check/merge_short_edges.hpp), the result is checked and reported instead, and written
// to OUT with OUT's stem + `_vertex_map.json` beside it only if it is acceptable.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "meshing/check/check_surface.hpp"
#include "meshing/check/merge_short_edges.hpp"
#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
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
  double merge_short_edges = 0;  // relative to the bbox's longest edge; 0: no repair
  std::string output;
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
  sub->add_option("--merge-short-edges", args->merge_short_edges,
                  "repair: merge every edge shorter than L x the bbox's longest edge into one of "
                  "its ends (where the surface stays a closed manifold), check the result and "
                  "write it to -o with a vertex map; the curved mesh then maps to that surface")
      ->check(CLI::PositiveNumber);
  sub->add_option("-o,--output", args->output,
                  "with --merge-short-edges: the repaired surface, and STEM_vertex_map.json "
                  "beside it (written only if it is acceptable)");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    auto progress = apply_global_options(args->global);
    if ((args->merge_short_edges > 0) != !args->output.empty())
      throw InputError("check: --merge-short-edges and -o go together");
    SurfaceMesh mesh = io::read_surface(args->input);
    nlohmann::json merge_json;
    std::string reported = args->input;
    std::filesystem::path map_path;
    if (args->merge_short_edges > 0) {
      const double length = args->merge_short_edges * bbox_longest_edge(mesh.V);
      check::MergeShortEdgesResult merged = check::merge_short_edges(mesh, {.max_length = length});
      const std::filesystem::path out(args->output);
      map_path = out.parent_path() / (out.stem().string() + "_vertex_map.json");
      merge_json = pipeline::merge_summary_json(merged, args->merge_short_edges, length);
      merge_json["output"] = args->output;
      merge_json["vertex_map_file"] = map_path.string();
      merge_json.update(pipeline::merge_map_json(merged));
      mesh = std::move(merged.mesh);
      reported = args->output;
    }
    check::CheckOptions options;
    options.self_intersections = !args->skip_self_intersections;
    const check::CheckReport report = check::check_surface(mesh, options, progress->callback());
    progress.reset();  // finish the progress line on stderr before the report on stdout
    if (!merge_json.is_null() && report.acceptable) {
      io::write_surface(args->output, mesh, io::surface_format_from_extension(args->output));
      nlohmann::json file = merge_json;
      file["input"] = args->input;
      write_text_file_atomic(map_path, file.dump(1) + "\n");
    }
    if (args->json) {
      nlohmann::json j = pipeline::check_report_json(report);
      j["input"] = reported;
      if (!merge_json.is_null()) {
        merge_json.erase("vertex_map");
        merge_json.erase("face_origin");
        merge_json["written"] = report.acceptable;
        j["merge_short_edges"] = merge_json;
      }
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      if (!merge_json.is_null()) {
        const std::string written =
            report.acceptable
                ? "is written to " + args->output + " (vertex map " + map_path.string() + ")"
                : std::string("is not acceptable and is not written");
        std::printf(
            "merged %d of %d edges shorter than %.4g (%.4g x the bbox's longest edge; %d left: "
            "merging them would break the manifold or turn a face by > 30 deg), longest "
            "merged %.4g; the repaired surface %s:\n",
            merge_json["merged"].get<int>(), merge_json["candidates"].get<int>(),
            merge_json["max_length"].get<double>(), args->merge_short_edges,
            merge_json["left"].get<int>(), merge_json["max_moved"].get<double>(), written.c_str());
      }
      print_human(reported, report);
    }
    std::fflush(stdout);
    return report.acceptable ? 0 : 2;
  });
}

}  // namespace curvefem::cli
