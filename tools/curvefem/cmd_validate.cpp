// `curvefem validate DIR [--json]`: re-checks a `mesh` output directory against its input with
// code paths separate from the mesher (meshing/curved/curved_validate.hpp): reads mesh.vtu,
// boundary_map.json and the input named in report.json, and prints what holds. Exit 3 naming the
// first failing tet / face / vertex if any guarantee fails.
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>

#include "meshing/core/error.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/io/boundary_map_io.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "pipeline/input_floors.hpp"
#include "pipeline/mesh_validity.hpp"
#include "pipeline/report_json.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {

using pipeline::curved_validation_json;

namespace {

struct ValidateArgs {
  std::string dir, input;
  double eps = -1;
  int subdivision = 0;
  bool json = false;
  GlobalOptions global;
};

}  // namespace

void register_validate(CLI::App& app) {
  auto args = std::make_shared<ValidateArgs>();
  CLI::App* sub =
      app.add_subcommand("validate", "independently re-check a `curvefem mesh` output directory");
  sub->add_option("dir", args->dir, "output folder of `curvefem mesh`")->required();
  sub->add_option("--input", args->input, "input surface (default: the one in report.json)");
  sub->add_option("--eps", args->eps, "distance bound (default: eps_rel of report.json)");
  sub->add_option("--subdivision", args->subdivision,
                  "flat triangles per curved edge for the embedding check (default 2K)");
  sub->add_flag("--json", args->json, "print the result as JSON");
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    auto progress = apply_global_options(args->global);
    const std::filesystem::path dir(args->dir);
    const std::filesystem::path report_path = dir / "report.json";
    std::ifstream rf(report_path);
    if (!rf) throw IoError(report_path.string() + ": cannot open (is this a mesh output?)");
    nlohmann::json report;
    try {
      report = nlohmann::json::parse(rf);
    } catch (const nlohmann::json::exception& e) {
      throw InputError(report_path.string() + ": not valid JSON: " + e.what());
    }
    std::string input_path = args->input;
    double eps = args->eps;
    try {
      if (input_path.empty()) input_path = report.at("input").get<std::string>();
      if (eps <= 0) eps = report.at("eps_rel").get<double>();
    } catch (const nlohmann::json::exception& e) {
      throw InputError(report_path.string() + ": missing input or eps_rel: " + e.what());
    }
    const SurfaceMesh input = io::read_surface(input_path);
    const io::VtuContent vtu = io::read_vtu(dir / "mesh.vtu");
    if (vtu.mesh.kind != CellKind::tetrahedron)
      throw InputError((dir / "mesh.vtu").string() + ": not a tetrahedral mesh");
    const io::SavedBoundaryMap saved = io::read_boundary_map(dir / "boundary_map.json");
    const BoundaryMap& map = saved.map;
    if (map.boundary.order != vtu.mesh.order)
      throw InputError((dir / "boundary_map.json").string() + ": order " +
                       std::to_string(map.boundary.order) + " differs from mesh.vtu's " +
                       std::to_string(vtu.mesh.order));
    const auto v = meshing::curved::validate_curved_mesh(vtu.mesh, map, input, args->subdivision);
    pipeline::MapRoundtrip trip;
    if (saved.fibers) trip = pipeline::map_roundtrip(map, *saved.fibers, input);
    const double roundtrip = trip.max_error_rel;
    const int roundtrip_failures = trip.failures;
    const bool ok = pipeline::curved_mesh_valid(v, eps, trip);
    const pipeline::InputFloors floors =
        pipeline::input_floors(input, map, vtu.mesh, v.cell_mips, v.cell_scaled_jacobian);
    progress.reset();
    if (args->json) {
      auto j = curved_validation_json(v, eps);
      j["map_roundtrip_checked"] = saved.fibers.has_value();
      j["map_roundtrip_max_error_rel"] = roundtrip;
      j["map_roundtrip_failures"] = roundtrip_failures;
      j["map_roundtrip_worst_vertex"] = trip.worst_vertex;
      j["map_roundtrip_first_failure"] = trip.first_failure;
      j["valid"] = ok;
      j["input_floors"] = nlohmann::ordered_json::parse(pipeline::input_floors_json(floors).dump());
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      std::printf("validate %s (input %s)\n", args->dir.c_str(), input_path.c_str());
      std::printf("  tets                 %d of order %d\n", v.tets, vtu.mesh.order);
      std::printf(
          "  det J certified      %s (%d non-positive, %d undecided%s)\n",
          v.certified() ? "yes" : "NO", v.non_positive_tets, v.undecided_tets,
          v.first_bad_tet >= 0 ? (", first tet " + std::to_string(v.first_bad_tet)).c_str() : "");
      std::printf("  min scaled Jacobian  %.4g, MIPS mean %.4g max %.4g\n", v.min_scaled_jacobian,
                  v.mean_mips, v.max_mips);
      std::printf("  boundary             %d faces, %d missing, %d extra, %d node mismatches\n",
                  v.boundary_faces, v.boundary_faces_missing, v.boundary_faces_extra,
                  v.boundary_node_mismatches);
      std::printf("  boundary embedded    %s (%d self-intersections at %d per edge)\n",
                  v.boundary_self_intersections == 0 ? "yes" : "NO", v.boundary_self_intersections,
                  v.subdivision);
      std::printf(
          "  boundary patches     (diag.) %d folded, %d with area element ratio < 0.1, min %.3g\n",
          v.boundary_faces_folded, v.boundary_faces_distorted, v.min_boundary_area_ratio);
      if (v.eps_field)
        std::printf(
            "  distance             max %.4g (eps field up to %.4g); max distance / local eps "
            "%.4g at input vertex %d%s\n",
            v.max_distance_rel, eps, v.max_scaled_distance_rel / eps, v.max_scaled_distance_vertex,
            v.max_scaled_distance_rel <= eps ? "" : "  EXCEEDS the local eps");
      else
        std::printf("  distance             max %.4g (eps %.4g) at input vertex %d%s\n",
                    v.max_distance_rel, eps, v.max_distance_vertex,
                    v.max_distance_rel <= eps ? "" : "  EXCEEDS eps");
      if (v.distance_points > 0)
        std::printf("  distance points      %d, max %.4g at point %d%s\n", v.distance_points,
                    v.points_max_distance_rel, v.points_max_distance_point,
                    v.bad_distance_points > 0                 ? "  BAD INPUT FACE IDS"
                    : v.points_max_scaled_distance_rel <= eps ? ""
                                                              : "  EXCEEDS eps");
      std::printf("  unmapped vertices    %d\n", v.unmapped_vertices);
      std::printf(
          "  input floors (diag.) %d of %d needle faces and %d of %d near folds of the input kept "
          "as they are; the worst tet is %son one\n",
          floors.needle_faces_kept, floors.needle_faces, floors.near_fold_edges_kept,
          floors.near_fold_edges,
          floors.worst_mips_tet_at_kept || floors.worst_scaled_jacobian_tet_at_kept ? "" : "not ");
      if (v.feature_edges > 0)
        std::printf(
            "  feature edges        %d, %d not along a boundary edge%s\n", v.feature_edges,
            v.features_off_edges,
            v.first_feature_off >= 0
                ? (" (first: map feature edge " + std::to_string(v.first_feature_off) + ")").c_str()
                : "");
      std::printf(
          "  phi chart (diag.)    %d of %d input faces inside one boundary face have a "
          "non-positive straight (u, v) image\n",
          v.flipped_input_faces, v.input_faces_checked);
      if (saved.fibers)
        std::printf(
            "  phi roundtrip        max %.3g (input vertex %d), %d failures%s\n", roundtrip,
            trip.worst_vertex, roundtrip_failures,
            trip.first_failure >= 0
                ? (" (first: input vertex " + std::to_string(trip.first_failure) + ")").c_str()
                : "");
      else
        std::printf("  phi roundtrip        not checked (no shell fibers in boundary_map.json)\n");
      std::printf("  result               %s (%.2f s)\n", ok ? "valid" : "INVALID", v.seconds);
      for (const std::string& defect : pipeline::curved_mesh_defects(v, eps, trip))
        std::printf("  defect               %s\n", defect.c_str());
    }
    std::fflush(stdout);
    return ok ? 0 : 3;
  });
}

}  // namespace curvefem::cli
