// `curvefem deform IN -o OUT.obj [--targets FILE] [--grow S] [--box B] [--iterations N]
// [--tolerance T] [--target-weight W] [--untangle [--flow-step D] [--flow-steps N]]
// [--report report.json] [--quiet]`: deform a closed surface toward positional targets (and/or a
// grown rest shape) without self-intersection: SCAF with a tetrahedral scaffold
// (meshing/param/scaf3d.hpp). With --untangle, a self-intersecting genus-0 input is flowed until
// embedded and pulled back toward itself in the scaffold (meshing/param/untangle.hpp). After every
// iteration the surface is checked for self-intersection by meshing/check (exact); at the end the
// object and scaffold tets are verified positive and tiling the box (meshing/tetfill's exact
// verifier). Exit 0 when both checks pass, 3 when not (no surface written; the report is), 2 for
// bad input (an open surface, a self-intersecting one without --untangle, a bad target).
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/param/deform.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {
namespace {

namespace pa = meshing::param;

struct DeformArgs {
  std::string input, output, targets, report;
  pa::Deform3dOptions options;
  bool untangle = false;
  bool no_way_back_targets = false;
  pa::UntangleOptions untangle_options;
  GlobalOptions global;
};

}  // namespace

void register_deform(CLI::App& app) {
  auto args = std::make_shared<DeformArgs>();
  CLI::App* sub = app.add_subcommand(
      "deform",
      "deform a closed surface toward targets without self-intersection (SCAF, tet scaffold)");
  sub->add_option("input", args->input, "closed surface (.obj .off .stl .ply .msh)")->required();
  sub->add_option("-o,--output", args->output, "deformed surface (same faces)")->required();
  sub->add_option("--targets", args->targets,
                  "positional targets: 'vertex x y z' per line (0-based vertex ids)");
  sub->add_option("--grow", args->options.grow,
                  "rest shape = the input scaled by this (e.g. 2: the object tries to double "
                  "in size inside its box)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--box", args->options.box_scale,
                  "scaffold box = the bounding box of the input and the targets, widened on "
                  "every side by (B - 1) / 2 x its longest extent")
      ->check(CLI::Range(1.01, 100.0));
  sub->add_option("--iterations", args->options.max_iterations, "maximum iterations")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--tolerance", args->options.tolerance,
                  "stop when the relative decrease of the objective is below this")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--target-weight", args->options.target_weight,
                  "weight of the targets (squared distances relative to the box diagonal)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--rebuild-quality", args->options.rebuild_quality,
                  "rebuild the scaffold only when its worst tet shape (6 sqrt2 V / l_rms^3) fell "
                  "below this x that of the last rebuild (default 0.5); 0: every iteration (the "
                  "thesis)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_flag("--sliver-rests", args->options.replace_slivers,
                "a scaffold tet below l^3 / 16 in volume (l: the surface's shortest edge) gets "
                "the regular tet of that volume as its rest, so the scaffold keeps sheets of the "
                "surface apart (thesis 3.2.2); off: every rest is the current shape");
  sub->add_option("--arap", args->options.arap_weight,
                  "weight of a surface ARAP term toward the input's shape (rotation-invariant per "
                  "vertex; with --untangle the thesis' way back); 0: none")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--untangle", args->untangle,
                "remove the input's self-intersections (genus 0): a conformalized mean curvature "
                "flow until embedded, then every vertex pulled back toward its input position "
                "inside the scaffold");
  sub->add_option("--flow-step", args->untangle_options.flow_step,
                  "--untangle: flow time step relative to the surface area")
      ->check(CLI::PositiveNumber);
  sub->add_option("--flow-steps", args->untangle_options.max_flow_steps,
                  "--untangle: at most this many flow steps")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--no-way-back-targets", args->no_way_back_targets,
                "--untangle: no positional targets on the way back, only the ARAP term (needs "
                "--arap)");
  sub->add_option("--report", args->report, "write report.json here");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    auto progress = apply_global_options(args->global);
    Stopwatch total;
    const SurfaceMesh mesh = io::read_surface(args->input);
    const io::SurfaceFormat format = io::surface_format_from_extension(args->output);
    std::vector<pa::PositionTarget> targets;
    if (!args->targets.empty()) targets = pa::read_target_file(args->targets, mesh.num_vertices());
    const ProgressFn report_progress = progress->callback();
    nlohmann::ordered_json iterations = nlohmann::ordered_json::array();
    pa::DeformRequest request;
    request.targets = targets;
    request.options = args->options;
    request.untangle = args->untangle;
    request.untangle_options = args->untangle_options;
    request.untangle_options.way_back_targets = !args->no_way_back_targets;
    request.observe = [&](const pa::Deform3dIteration& st, const Eigen::MatrixXd&, int pairs) {
      iterations.push_back({{"iteration", st.iteration},
                            {"energy", st.energy},
                            {"objective", st.objective},
                            {"target_error_rel", st.target_error},
                            {"arap", st.arap},
                            {"step", st.step},
                            {"max_step", st.max_step},
                            {"backtracks", st.backtracks},
                            {"min_singular_value", st.min_singular},
                            {"max_singular_value", st.max_singular},
                            {"min_tet_volume_rel", st.min_volume_rel},
                            {"scaffold_tets", st.scaffold_tets},
                            {"scaffold_rebuilt", st.scaffold_rebuilt},
                            {"slivers", st.slivers},
                            {"slivers_kept", st.slivers_kept},
                            {"scaffold_min_quality", st.scaffold_min_quality},
                            {"self_intersecting_pairs", pairs},
                            {"time_s",
                             {{"iteration", st.seconds},
                              {"scaffold", st.scaffold_s},
                              {"assemble", st.assemble_s},
                              {"solve", st.solve_s},
                              {"line_search", st.line_search_s}}}});
      if (report_progress)
        report_progress("scaf3d", double(st.iteration) / std::max(1, args->options.max_iterations));
    };
    const pa::DeformOutcome outcome = pa::deform_checked(mesh, request);
    const pa::Deform3dResult& result = outcome.result;
    nlohmann::ordered_json untangle_json = nullptr;
    if (outcome.untangle) {
      const pa::UntangleResult& u = *outcome.untangle;
      untangle_json = {{"input_self_intersecting_pairs", u.input_pairs},
                       {"genus", u.genus},
                       {"flow_step", args->untangle_options.flow_step},
                       {"flow_steps", u.flow_pairs.size()},
                       {"pairs_after_each_flow_step", u.flow_pairs},
                       {"flow_s", u.flow_seconds},
                       {"max_distance_to_input_rel", u.max_distance_rel},
                       {"mean_distance_to_input_rel", u.mean_distance_rel},
                       {"way_back_targets", !args->no_way_back_targets},
                       {"edge_length_error_mean", u.edge_length_error_mean},
                       {"edge_length_error_max", u.edge_length_error_max}};
    }
    const bool ok = outcome.valid();
    // A surface that failed a check is not written (exit 3); the report says why.
    if (ok) {
      SurfaceMesh out = mesh;
      out.V = result.V;
      io::write_surface(args->output, out, format);
    }
    progress.reset();
    const auto& h = result.history;
    if (!args->report.empty()) {
      nlohmann::ordered_json report = {
          {"input", args->input},
          {"output", args->output},
          {"targets", args->targets.empty() ? nlohmann::ordered_json(nullptr)
                                            : nlohmann::ordered_json(args->targets)},
          {"target_count", args->untangle ? std::size_t(mesh.num_vertices()) : targets.size()},
          {"untangle", untangle_json},
          {"grow", args->options.grow},
          {"box_scale", args->options.box_scale},
          {"arap_weight", args->options.arap_weight},
          {"vertices", mesh.num_vertices()},
          {"faces", mesh.num_faces()},
          {"object_tets", result.object_tets.rows()},
          {"scaffold_tets", result.scaffold_tets.rows()},
          {"iterations", h.back().iteration},
          {"stop_reason", result.stop_reason},
          {"scaffold_rebuild_failures", result.scaffold_failures},
          {"scaffold_kept", result.scaffold_kept},
          {"rebuild_quality", args->options.rebuild_quality},
          {"sliver_rests", args->options.replace_slivers},
          {"initial_objective", h.front().objective},
          {"objective", h.back().objective},
          {"initial_energy", h.front().energy},
          {"energy", h.back().energy},
          {"initial_target_error_rel", h.front().target_error},
          {"target_error_rel", h.back().target_error},
          {"min_singular_value", h.back().min_singular},
          {"max_singular_value", h.back().max_singular},
          {"self_intersecting_pairs", outcome.final_pairs},
          {"max_self_intersecting_pairs_over_iterations", outcome.max_pairs_over_iterations},
          {"naive_self_intersecting_pairs", targets.empty() && !args->untangle
                                                ? nlohmann::ordered_json(nullptr)
                                                : nlohmann::ordered_json(outcome.naive_pairs)},
          {"non_positive_tets", outcome.tiling.non_positive_tets},
          {"tiling_boundary_mismatches", outcome.tiling.boundary_mismatches},
          {"tiling_volume_error_rel", outcome.tiling.volume_error_rel},
          {"valid", ok},
          {"history", iterations},
          {"time_s",
           {{"scaf3d", result.seconds},
            {"per_iteration", h.back().iteration > 0 ? result.seconds / h.back().iteration : 0.0},
            {"checks", outcome.check_seconds},
            {"total", total.seconds()}}}};
      write_text_file_atomic(args->report, report.dump(2) + "\n");
    }
    std::printf(
        "deform: %d faces, %lld object tets: objective %.6g -> %.6g, energy %.6g, target error "
        "%.3g of the box diagonal, %d iterations (%s); self-intersecting pairs %d (naive targets: "
        "%d), non-positive tets %lld: %s; %.2f s\n",
        mesh.num_faces(), (long long)result.object_tets.rows(), h.front().objective,
        h.back().objective, h.back().energy, h.back().target_error, h.back().iteration,
        result.stop_reason.c_str(), outcome.final_pairs, outcome.naive_pairs,
        outcome.tiling.non_positive_tets, ok ? "valid" : "NOT VALID", total.seconds());
    std::fflush(stdout);
    return ok ? 0 : 3;
  });
}

}  // namespace curvefem::cli
