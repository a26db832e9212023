// `curvefem param IN -o OUT.obj [--seams FILE] [--iterations N] [--tolerance T] [--weights W]
// [--init-uv] [--report report.json] [--no-check-iterations] [--quiet]`: bijective UV
// parameterization (SCAF, meshing/param). Charts: OBJ groups, then cut along the seams (0-based
// vertex id pairs); each must be a disk. Initial map: Tutte on a circle per chart, or with
// --init-uv the input OBJ's vt (verified bijective by the exact checker first, else InputError).
// Output: the OBJ with `vt` (a seam vertex has several) and, with --report, the energy, singular
// values, step, scaffold size and time of every iteration, and flips / overlaps counted by the
// independent exact checker (meshing/param/uv_check.hpp) after every iteration (only at the end
// with --no-check-iterations). Exit 0 when the final map is verified bijective, 3 when not, 2 for
// bad input (e.g. a chart that is not a disk).
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/param/cut_mesh.hpp"
#include "meshing/param/scaf.hpp"
#include "meshing/param/seam_file.hpp"
#include "meshing/param/tutte.hpp"
#include "meshing/param/uv_check.hpp"
#include "meshing/param/uv_obj.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {
namespace {

namespace pa = meshing::param;

struct ParamArgs {
  std::string input, output, seams, report, weights = "mean-value";
  int iterations = 50;
  double tolerance = 1e-6;
  int newton = pa::ScafOptions{}.newton_iterations;
  bool no_check_iterations = false;
  bool init_uv = false;
  GlobalOptions global;
};

nlohmann::ordered_json check_json(const pa::UvCheck& c) {
  return {{"flips", c.flips},
          {"overlaps", c.overlaps},
          {"nested_charts", c.nested_charts},
          {"bijective", c.bijective()},
          {"area_rel_error", c.area_rel_error}};
}

}  // namespace

void register_param(CLI::App& app) {
  auto args = std::make_shared<ParamArgs>();
  CLI::App* sub = app.add_subcommand(
      "param", "bijective UV parameterization of disk charts (SCAF): OBJ with vt + report");
  sub->add_option("input", args->input, "surface (.obj .off .stl .ply .msh); OBJ groups = charts")
      ->required();
  sub->add_option("-o,--output", args->output, "output OBJ with vt")->required();
  sub->add_option("--seams", args->seams,
                  "text file of seam edges to cut along: two 0-based vertex ids per line");
  sub->add_option("--iterations", args->iterations, "maximum SCAF iterations")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--tolerance", args->tolerance,
                  "stop when the relative energy decrease of an iteration is below this")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--newton", args->newton,
                  "then at most this many projected Newton iterations from the SLIM result, "
                  "until the relative energy decrease is below 1e-12 (default 10; 0: none)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--weights", args->weights, "Tutte weights: mean-value or uniform")
      ->check(CLI::IsMember({"mean-value", "uniform"}));
  sub->add_option("--report", args->report, "write report.json here");
  sub->add_flag(
      "--init-uv", args->init_uv,
      "start from the input OBJ's texture coordinates (vt; must be a bijective map of the "
      "charts) instead of Tutte's embedding");
  sub->add_flag("--no-check-iterations", args->no_check_iterations,
                "run the exact flip/overlap check on the final map only");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    auto progress = apply_global_options(args->global);
    Stopwatch total;
    const SurfaceMesh mesh = io::read_surface(args->input);
    std::vector<std::array<int, 2>> seams;
    if (!args->seams.empty()) seams = pa::read_seam_file(args->seams);
    Stopwatch stage;
    const pa::CutMesh cut = pa::cut_into_charts(mesh, seams);
    const double cut_s = stage.seconds();
    stage.reset();
    Eigen::MatrixXd uv0;
    if (args->init_uv) {
      uv0 = pa::uv_from_texture(cut, pa::read_obj_texture(args->input));
      const pa::UvCheck given = pa::check_uv_map(uv0, cut.F);
      if (!given.bijective())
        throw InputError("--init-uv: the input's texture coordinates are not a bijective map: " +
                         std::to_string(given.flips) + " flipped or degenerate faces, " +
                         std::to_string(given.overlaps) + " intersecting boundary edge pairs, " +
                         std::to_string(given.nested_charts) + " nested charts");
    } else {
      uv0 = pa::tutte_layout(cut, args->weights == "uniform" ? pa::TutteWeights::uniform
                                                             : pa::TutteWeights::mean_value);
    }
    const double tutte_s = stage.seconds();

    pa::ScafOptions options;
    options.max_iterations = args->iterations;
    options.tolerance = args->tolerance;
    options.newton_iterations = args->newton;
    nlohmann::ordered_json iterations = nlohmann::ordered_json::array();
    double check_s = 0;
    long long worst_flips = 0, worst_overlaps = 0, worst_nested = 0;
    const ProgressFn report_progress = progress->callback();
    int newton_done = 0;
    options.on_iteration = [&](const pa::IterationStats& st, const Eigen::MatrixXd& uv,
                               const pa::Scaffold&) {
      nlohmann::ordered_json j = {{"iteration", st.iteration},
                                  {"method", st.iteration == 0 ? "initial"
                                             : st.newton       ? "newton"
                                                               : "slim"},
                                  {"energy", st.energy},
                                  {"objective", st.objective},
                                  {"lambda", st.lambda},
                                  {"step", st.step},
                                  {"max_step", st.max_step},
                                  {"backtracks", st.backtracks},
                                  {"fallback", st.fallbacks > 0},
                                  {"regularisation", st.regularisation},
                                  {"min_singular_value", st.min_singular},
                                  {"max_singular_value", st.max_singular},
                                  {"scaffold_vertices", st.scaffold_vertices},
                                  {"scaffold_faces", st.scaffold_faces},
                                  {"time_s",
                                   {{"iteration", st.seconds},
                                    {"scaffold", st.scaffold_s},
                                    {"assemble", st.assemble_s},
                                    {"solve", st.solve_s},
                                    {"line_search", st.line_search_s}}}};
      if (!args->no_check_iterations) {
        Stopwatch c;
        const pa::UvCheck check = pa::check_uv_map(uv, cut.F);
        check_s += c.seconds();
        worst_flips = std::max(worst_flips, check.flips);
        worst_overlaps = std::max(worst_overlaps, check.overlaps);
        worst_nested = std::max(worst_nested, check.nested_charts);
        j["flips"] = check.flips;
        j["overlaps"] = check.overlaps;
        j["nested_charts"] = check.nested_charts;
      }
      if (st.newton) j["gradient_norm"] = st.gradient_norm;
      iterations.push_back(j);
      if (report_progress)
        report_progress(st.newton ? "newton" : "scaf",
                        st.newton ? double(++newton_done) / std::max(1, args->newton)
                                  : double(st.iteration) / std::max(1, args->iterations));
    };
    const pa::ScafResult result = pa::scaf_optimize(cut, uv0, options);
    stage.reset();
    const pa::UvCheck final_check = pa::check_uv_map(result.uv, cut.F);
    check_s += stage.seconds();
    pa::write_uv_obj(args->output, mesh, cut, result.uv);
    progress.reset();

    const auto& h = result.history;
    const int done = h.back().iteration;
    double iteration_s = 0;
    for (std::size_t i = 1; i < h.size(); ++i) iteration_s += h[i].seconds;
    if (!args->report.empty()) {
      nlohmann::ordered_json report = {
          {"input", args->input},
          {"output", args->output},
          {"seams", args->seams.empty() ? nlohmann::ordered_json(nullptr)
                                        : nlohmann::ordered_json(args->seams)},
          {"vertices", mesh.num_vertices()},
          {"faces", mesh.num_faces()},
          {"uv_vertices", cut.num_uv_vertices()},
          {"charts", cut.num_charts},
          {"initial_map", args->init_uv ? "input vt" : "tutte"},
          {"tutte_weights",
           args->init_uv ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(args->weights)},
          {"solver", result.solver},
          {"iterations", done},
          {"stop_reason", result.stop_reason},
          {"newton_iterations", result.newton_iterations},
          {"newton_stop_reason", args->newton > 0
                                     ? nlohmann::ordered_json(result.newton_stop_reason)
                                     : nlohmann::ordered_json(nullptr)},
          {"initial_energy", h.front().energy},
          {"energy", h.back().energy},
          {"min_singular_value", h.back().min_singular},
          {"max_singular_value", h.back().max_singular},
          {"flips", final_check.flips},
          {"overlaps", final_check.overlaps},
          {"nested_charts", final_check.nested_charts},
          {"bijective", final_check.bijective()},
          {"final_check", check_json(final_check)},
          {"checked_every_iteration", !args->no_check_iterations},
          {"max_flips_over_iterations", args->no_check_iterations
                                            ? nlohmann::ordered_json(nullptr)
                                            : nlohmann::ordered_json(worst_flips)},
          {"max_overlaps_over_iterations",
           args->no_check_iterations ? nlohmann::ordered_json(nullptr)
                                     : nlohmann::ordered_json(worst_overlaps + worst_nested)},
          {"history", iterations},
          {"time_s",
           {{"cut", cut_s},
            {"tutte", tutte_s},
            {"scaf", result.seconds},
            {"per_iteration", done > 0 ? iteration_s / done : 0.0},
            {"checks", check_s},
            {"total", total.seconds()}}}};
      write_text_file_atomic(args->report, report.dump(2) + "\n");
    }
    std::printf(
        "param: %d chart(s), %d faces: energy %.10g -> %.10g in %d iterations (%s; %d Newton%s%s), "
        "%.3g s/iteration; "
        "flips %lld, overlaps %lld, nested %lld: %s; %.2f s\n",
        cut.num_charts, mesh.num_faces(), h.front().energy, h.back().energy, done,
        result.stop_reason.c_str(), result.newton_iterations,
        result.newton_stop_reason.empty() ? "" : ", ", result.newton_stop_reason.c_str(),
        done > 0 ? iteration_s / done : 0.0, final_check.flips, final_check.overlaps,
        final_check.nested_charts, final_check.bijective() ? "bijective" : "NOT BIJECTIVE",
        total.seconds());
    std::fflush(stdout);
    return final_check.bijective() ? 0 : 3;
  });
}

}  // namespace curvefem::cli
