// `curvefem remesh INPUT -o OUT.obj --algorithm shortest-collapse|qslim|isotropic
//  [--target-faces N | --target-edge R] [--envelope R] [--iterations K] [--threads N]`
// Runs one surface algorithm of meshing/editing, writes OUT.obj and OUT.json (counts, quality,
// deviation from the input, per-pass scheduler statistics, times) and prints one summary line.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/editing/algorithms/surface_remeshing.hpp"
#include "meshing/io/surface_io.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {
namespace {

namespace ed = meshing::editing;

struct RemeshArgs {
  std::string input, output, algorithm;
  std::size_t target_faces = 0;
  double target_edge = 0, envelope = 0;
  int iterations = 5;
  GlobalOptions global;
};

nlohmann::ordered_json quality_json(const ed::SurfaceQuality& q, double unit) {
  nlohmann::ordered_json hist = nlohmann::ordered_json::object();
  for (const auto& [valence, count] : q.valence_histogram) hist[std::to_string(valence)] = count;
  return {{"vertices", q.vertices},
          {"faces", q.faces},
          {"min_angle_deg", q.min_angle_deg},
          {"max_angle_deg", q.max_angle_deg},
          {"min_edge", q.min_edge},
          {"mean_edge", q.mean_edge},
          {"max_edge", q.max_edge},
          {"valence_histogram", hist},
          {"max_deviation", q.max_deviation},
          {"max_deviation_rel", unit > 0 ? q.max_deviation / unit : 0.0},
          {"max_deviation_from_input", q.max_deviation_from_reference},
          {"max_deviation_from_input_rel", unit > 0 ? q.max_deviation_from_reference / unit : 0.0}};
}

}  // namespace

void register_remesh(CLI::App& app) {
  auto args = std::make_shared<RemeshArgs>();
  CLI::App* sub =
      app.add_subcommand("remesh", "simplify or remesh a triangle surface (meshing/editing)");
  sub->add_option("input", args->input, "surface file (.obj .off .stl .ply .msh)")->required();
  sub->add_option("-o,--output", args->output,
                  "output surface (.obj, .off, .ply, .stl); OUT.json is written beside it")
      ->required();
  sub->add_option("--algorithm", args->algorithm, "shortest-collapse | qslim | isotropic")
      ->required()
      ->check(CLI::IsMember({"shortest-collapse", "qslim", "isotropic"}));
  auto* faces =
      sub->add_option("--target-faces", args->target_faces, "face budget (collapse algorithms)");
  auto* edge = sub->add_option("--target-edge", args->target_edge,
                               "target edge length, absolute (isotropic)");
  faces->excludes(edge);
  sub->add_option("--envelope", args->envelope,
                  "keep the surface within this distance of the input (absolute; 0 = off)");
  sub->add_option("--iterations", args->iterations, "isotropic remeshing rounds (default 5)");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    auto progress = apply_global_options(args->global);
    Stopwatch total;
    ed::RemeshOptions options;
    if (args->algorithm == "qslim")
      options.algorithm = ed::RemeshAlgorithm::qslim;
    else if (args->algorithm == "isotropic")
      options.algorithm = ed::RemeshAlgorithm::isotropic;
    if (options.algorithm == ed::RemeshAlgorithm::isotropic && args->target_edge <= 0)
      throw InputError("--algorithm isotropic needs --target-edge R (R > 0)");
    if (options.algorithm != ed::RemeshAlgorithm::isotropic && args->target_faces == 0)
      throw InputError("--algorithm " + args->algorithm + " needs --target-faces N (N > 0)");
    options.target_faces = args->target_faces;
    options.target_edge = args->target_edge;
    options.envelope = args->envelope;
    options.iterations = args->iterations;
    options.threads = args->global.threads > 0
                          ? args->global.threads
                          : int(std::max(1u, std::thread::hardware_concurrency()));
    Stopwatch read_clock;
    const SurfaceMesh input = io::read_surface(args->input);
    const double read_s = read_clock.seconds();
    const ed::RemeshResult result = ed::remesh(input, options);
    Stopwatch quality_clock;
    const ed::SurfaceQuality quality = ed::measure_quality(result.mesh, input);
    const double quality_s = quality_clock.seconds();
    const double unit = bbox_longest_edge(input.V);

    nlohmann::ordered_json passes = nlohmann::ordered_json::array();
    for (const auto& [name, s] : result.passes)
      passes.push_back({{"pass", name},
                        {"attempted", s.attempted},
                        {"succeeded", s.succeeded},
                        {"rejected_before", s.rejected_before},
                        {"rejected_topology", s.rejected_topology},
                        {"rejected_after", s.rejected_after},
                        {"rejected_invariant", s.rejected_invariant},
                        {"stale", s.stale_tuple + s.stale_priority},
                        {"lock_failures", s.lock_failures},
                        {"serial_tail", s.serial_tail},
                        {"time_s", s.seconds}});
    nlohmann::ordered_json report = {
        {"input", args->input},
        {"output", args->output},
        {"algorithm", args->algorithm},
        {"threads", options.threads},
        {"target_faces", options.target_faces},
        {"target_edge", options.target_edge},
        {"envelope", options.envelope},
        {"input_vertices", input.num_vertices()},
        {"input_faces", input.num_faces()},
        {"bbox_longest_edge", unit},
        {"quality", quality_json(quality, unit)},
        {"passes", passes},
        {"time_s", {{"read", read_s}, {"remesh", result.seconds}, {"quality", quality_s}}}};
    const std::filesystem::path out(args->output);
    io::write_surface(out, result.mesh, io::surface_format_from_extension(out));
    std::filesystem::path json_path = out;
    json_path.replace_extension(".json");
    report["time_s"]["total"] = total.seconds();
    write_text_file_atomic(json_path, report.dump(2) + "\n");
    progress.reset();
    std::printf(
        "remesh %s: %d -> %zu faces in %.2f s (%d thread%s); min angle %.1f deg, max deviation "
        "%.3g%% of bbox; %s\n",
        args->algorithm.c_str(), input.num_faces(), quality.faces, result.seconds, options.threads,
        options.threads == 1 ? "" : "s", quality.min_angle_deg,
        unit > 0 ? 100.0 * quality.max_deviation / unit : 0.0, json_path.string().c_str());
    std::fflush(stdout);
    return 0;
  });
}

}  // namespace curvefem::cli
