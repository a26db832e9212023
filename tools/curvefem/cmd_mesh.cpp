// `curvefem mesh INPUT -o DIR [--order K] [--eps R] [--features FILE | --feature-angle DEG |
// --no-features] [--thickness R] [--threads N]`: a coarse curved tet mesh of order K whose
// boundary maps bijectively to the input (meshing/curved). Writes mesh.vtu (Lagrange cells),
// mesh.msh (Gmsh 4.1), boundary_map.json and report.json; every guarantee in the report comes from
// validate_curved_mesh, not from the mesher. Exit 2 for an input `curvefem check` rejects, 3 when
// a guarantee fails (outputs are still written, with the failure named in report.json).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "mapping/boundary_inverse.hpp"
#include "meshing/check/check_surface.hpp"
#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/curved/curved_mesher.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/curved/features.hpp"
#include "meshing/io/boundary_map_io.hpp"
#include "meshing/io/msh_io.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "meshing/shell/fibers_of.hpp"
#include "pipeline/eps_field.hpp"
#include "pipeline/input_floors.hpp"
#include "pipeline/mesh_dir.hpp"
#include "pipeline/mesh_validity.hpp"
#include "pipeline/report_json.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {

using pipeline::curved_validation_cell_fields;
using pipeline::curved_validation_json;

namespace {

namespace cv = meshing::curved;

struct MeshArgs {
  std::string input, output, features, constraints, eps_field;
  std::vector<std::string> eps_by_tag;
  int eps_samples = 0;
  int order = 3;
  double eps = 1e-2, thickness = 0.02, thickness_per_edge = 1.0, feature_angle = 60;
  std::vector<double> eps_levels;
  bool no_features = false, exterior = false, nondeterministic = false, no_recurve = false,
       low_degree_slabs = false, no_pan = false, no_feature_chains = false,
       linear_coarsening = false, no_curved_repair = false, no_two_phase = false,
       no_concurrent_linear_phase = false, no_embed_boundary = false;
  double split_mips = 0;
  double max_edge_per_thickness = meshing::curved::CurvedMeshOptions{}.max_edge_per_thickness;
  double thin_refine_ratio = meshing::curved::CurvedMeshOptions{}.thin_refine_ratio;
  double shape_refine = meshing::curved::CurvedMeshOptions{}.shape_refine;
  double shape_refine_spike_angle = meshing::curved::CurvedMeshOptions{}.shape_refine_spike_angle;
  double shape_slack = meshing::curved::CurvedMeshOptions{}.shape_slack;
  double feature_min_size = -1;  // unset: the default for detected features, 0 for a file
  double feature_end_trim = -1;  // likewise
  double curve_quality_floor = meshing::curved::CurvedMeshOptions{}.curve_quality_floor;
  double curve_distortion_floor = meshing::curved::CurvedMeshOptions{}.curve_distortion_floor;
  double curved_min_area_ratio = meshing::curved::CurvedMeshOptions{}.curved_min_area_ratio;
  int shell_zoom_passes = meshing::curved::CurvedMeshOptions{}.shell_zoom_passes;
  double shell_pillar_cos = meshing::curved::CurvedMeshOptions{}.shell_pillar_cos;
  double shell_pillar_cos_relative = meshing::curved::CurvedMeshOptions{}.shell_pillar_cos_relative;
  int optimize_sweeps = meshing::curved::OptimizeOptions{}.sweeps;
  int optimize_node_sweeps = meshing::curved::OptimizeOptions{}.node_sweeps;
  int optimize_worst_sweeps = meshing::curved::OptimizeOptions{}.worst_sweeps;
  int optimize_mean_sweeps = meshing::curved::OptimizeOptions{}.mean_sweeps;
  bool optimize_mean_free_nodes = false;
  double optimize_worst_mips = meshing::curved::OptimizeOptions{}.worst_mips;
  double optimize_worst_mips_sj_slack = meshing::curved::OptimizeOptions{}.worst_mips_sj_slack;
  int optimize_edit_passes = meshing::curved::CurvedEditOptions{}.passes;
  double optimize_edit_energy = meshing::curved::CurvedEditOptions{}.energy;
  double optimize_edit_locked_mips = meshing::curved::CurvedEditOptions{}.locked_mips;
  bool optimize_edit_splits = meshing::curved::CurvedEditOptions{}.splits;
  bool optimize_no_mean_flips = !meshing::curved::CurvedEditOptions{}.mean_flips;
  double optimize_node_energy = meshing::curved::OptimizeOptions{}.node_energy;
  double padding = 0.25;
  double merge_short_edges = 0;  // relative to the bbox's longest edge; 0: the input as it is
  GlobalOptions global;
};

// Constraint points: a JSON list of [x, y, z], or {"points": [...]}.
std::vector<Eigen::Vector3d> read_constraint_file(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw IoError(path + ": cannot open the constraint point file");
  std::vector<Eigen::Vector3d> points;
  try {
    const nlohmann::json j = nlohmann::json::parse(f);
    const nlohmann::json& list = j.is_object() ? j.at("points") : j;
    if (!list.is_array()) throw InputError(path + ": expected a list of [x, y, z] points");
    for (std::size_t i = 0; i < list.size(); ++i) {
      if (!list[i].is_array() || list[i].size() != 3 || !list[i][0].is_number() ||
          !list[i][1].is_number() || !list[i][2].is_number())
        throw InputError(path + ": constraint point " + std::to_string(i) +
                         " is not a list of three numbers");
      points.emplace_back(list[i][0].get<double>(), list[i][1].get<double>(),
                          list[i][2].get<double>());
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not a JSON list of [x, y, z] points: " + e.what());
  }
  return points;
}

std::vector<std::array<int, 2>> read_feature_file(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw IoError(path + ": cannot open the feature file");
  std::vector<std::array<int, 2>> edges;
  try {
    const nlohmann::json j = nlohmann::json::parse(f);
    const nlohmann::json& list = j.is_object() ? j.at("edges") : j;
    for (std::size_t i = 0; i < list.size(); ++i) {
      if (!list[i].is_array() || list[i].size() != 2)
        throw InputError(path + ": feature edge " + std::to_string(i) +
                         " is not a pair of vertex ids");
      edges.push_back({list[i][0].get<int>(), list[i][1].get<int>()});
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not a JSON list of vertex-index pairs: " + e.what());
  }
  return edges;
}

}  // namespace

void register_mesh(CLI::App& app) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* sub = app.add_subcommand(
      "mesh", "coarse curved tetrahedral mesh of order K with a certified bijective boundary map");
  sub->add_option("input", args->input, "closed, oriented surface (.obj .off .stl .ply .msh)")
      ->required();
  sub->add_option("-o,--output", args->output, "output folder")->required();
  sub->add_option("--order", args->order, "geometric order K (1..4)")->check(CLI::Range(1, 4));
  sub->add_option("--eps", args->eps, "distance bound, relative to the longest bbox edge")
      ->check(CLI::PositiveNumber);
  sub->add_option("--thickness", args->thickness, "shell half-thickness cap (relative)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--thickness-per-edge", args->thickness_per_edge,
                  "initial shell half-thickness cap per vertex, x its mean input edge length "
                  "(0: off; default 1)")
      ->check(CLI::NonNegativeNumber);
  auto* ff = sub->add_option("--features", args->features,
                             "JSON list of feature edges as input vertex-index pairs");
  auto* fa = sub->add_option("--feature-angle", args->feature_angle,
                             "mark edges whose dihedral angle exceeds DEG degrees (default 60)");
  auto* fn = sub->add_flag("--no-features", args->no_features, "no feature edges");
  sub->add_option("--feature-min-size", args->feature_min_size,
                  "feature curves (connected feature edges) whose bounding box is smaller than "
                  "this many eps are not kept as features (default 2 for detected features, 0 "
                  "with --features; 0: keep all)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--feature-end-trim", args->feature_end_trim,
                  "open ends of feature curves are cut back by this many eps (default 0; 0 with "
                  "--features unless given; 0: off)")
      ->check(CLI::NonNegativeNumber);
  ff->excludes(fa)->excludes(fn);
  fa->excludes(fn);
  sub->add_option("--optimize-sweeps", args->optimize_sweeps,
                  "vertex-smoothing sweeps of the inner surface and interior (0: off)")
      ->check(CLI::Range(0, 100));
  sub->add_option("--optimize-node-sweeps", args->optimize_node_sweeps,
                  "sweeps moving single high-order nodes of distorted curved cells, after the "
                  "vertex smoothing (default 4; 0: off)")
      ->check(CLI::Range(0, 100));
  sub->add_option("--optimize-worst-sweeps", args->optimize_worst_sweeps,
                  "last, sweeps moving the free corners of cells whose sampled scaled Jacobian "
                  "is below 0.02 to raise their star's minimum (default 3; 0: off)")
      ->check(CLI::Range(0, 100));
  sub->add_option("--optimize-mean-sweeps", args->optimize_mean_sweeps,
                  "after the worst-cell sweeps, sweeps lowering the summed curved MIPS of stars "
                  "holding a cell above 50, no cell's scaled Jacobian below min(before, 0.1) nor "
                  "its MIPS above max(before, 50) (0: off)")
      ->check(CLI::Range(0, 100));
  sub->add_flag("--optimize-mean-free-nodes", args->optimize_mean_free_nodes,
                "in that polish, let single high-order nodes raise their cells' Jacobian "
                "variation: a lower mean curved MIPS, but a larger FEM error on the curved maps");
  sub->add_option("--optimize-worst-mips", args->optimize_worst_mips,
                  "then the same sweeps lower the worst curved MIPS of stars holding a cell "
                  "above M, at most 100 stars a sweep, keeping their scaled Jacobians above "
                  "min(before, 0.02) less the slack below (default 2000; 0: off)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option(
         "--optimize-worst-mips-sj-slack", args->optimize_worst_mips_sj_slack,
         "in that search, the fraction by which a star's smallest scaled Jacobian may "
         "fall where its worst cell is above 1e4, never below the smaller of 0.002 and its "
         "value before (default 0.1; 0: it may not fall)")
      ->check(CLI::Range(0.0, 0.5));
  sub->add_option("--optimize-node-energy", args->optimize_node_energy,
                  "node phase: move only nodes of stars with a sample whose "
                  "conformal AMIPS energy (1 for a regular tet) exceeds E (default 10)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--optimize-edit-passes", args->optimize_edit_passes,
                  "rounds of edge collapses and 2-3/3-2/4-4 flips of the curved tets before the "
                  "smoothing (default 2; 0: off)")
      ->check(CLI::Range(0, 100));
  sub->add_flag("--optimize-edit-splits", args->optimize_edit_splits,
                "the curved edits also split interior edges of cells with a scaled Jacobian below "
                "0.01 (kept when the cavity's worst scaled Jacobian rises by half)");
  sub->add_flag("--optimize-no-mean-flips", args->optimize_no_mean_flips,
                "skip the last curved edits' 2-3/3-2/4-4 flips around cells above curved MIPS 30 "
                "that lower the mesh's mean curved MIPS (no new cell above max(the replaced "
                "cells' worst, 30) nor below min(their smallest scaled Jacobian, 0.1))");
  sub->add_option("--optimize-edit-locked-mips", args->optimize_edit_locked_mips,
                  "curved edits: no new cell with all four corners fixed (on the curved surface or "
                  "a boundary face; the smoothing cannot move them) and a curved MIPS above M, "
                  "unless the cells it replaces held a worse one (default 1e4; 0: off)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--optimize-edit-energy", args->optimize_edit_energy,
                  "curved edits: only cells whose mean conformal AMIPS energy exceeds E are "
                  "targets (default 2)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--nondeterministic", args->nondeterministic,
                "coarsen on all --threads workers: faster, but the mesh varies from run to run");
  sub->add_option("--constraints", args->constraints,
                  "JSON list of [x, y, z] points on the input where the distance bound must also "
                  "hold");
  sub->add_option("--eps-levels", args->eps_levels,
                  "several distance bounds from one shell and one coarsening (e.g. "
                  "0.04,0.02,0.01): the finest level coarsens the shell, each coarser one "
                  "resumes from the finer level's coarse shell; each level is meshed, validated "
                  "and written to OUTPUT/eps_<value>/, with OUTPUT/levels.json")
      ->delimiter(',')
      ->excludes("--eps")
      ->check(CLI::PositiveNumber);
  sub->add_option("--eps-field", args->eps_field,
                  "spatially varying distance bound: an expression of x, y, z (muparser), "
                  "relative to the longest bbox edge like --eps; the bound at x is "
                  "min(--eps, EXPR), e.g. \"x < 0 ? 0.002 : 0.01\"");
  sub->add_option("--eps-by-tag", args->eps_by_tag,
                  "distance bounds per face tag of the input: TAG=EPS,... (TAG a tag value or an "
                  "OBJ group / MSH physical name; EPS relative like --eps); the bound at a vertex "
                  "is the smallest of --eps, --eps-field and the bounds of the faces around it")
      ->delimiter(',');
  sub->add_option("--eps-samples", args->eps_samples,
                  "also bound the distance at the non-corner points of the degree-L barycentric "
                  "lattice of every input triangle (L >= 2; 0: vertices only)")
      ->check(CLI::Range(0, 16));
  sub->add_flag("--no-pan", args->no_pan,
                "coarsening does not move middle vertices to neighbouring input vertices where "
                "their star is better shaped");
  sub->add_flag("--no-feature-chains", args->no_feature_chains,
                "keep every feature vertex as a coarse vertex (by default the coarsening runs "
                "along feature chains, their vertices snapped onto the coarse feature edge in a "
                "reference copy of the input)");
  sub->add_flag("--linear-coarsening", args->linear_coarsening,
                "bound the distance on the linear middle surface during coarsening (by default, "
                "at order >= 2, an input vertex may lie up to 3 eps from it when the face's fully "
                "curved patch is within eps of it)");
  sub->add_flag("--no-curved-repair", args->no_curved_repair,
                "when the curved surface misses eps after the curved-aware coarsening, coarsen "
                "the input again instead of splitting the coarse faces that missed (the default)");
  sub->add_option("--split-mips", args->split_mips,
                  "coarsening also splits the longest edge of middle triangles whose 2-D MIPS "
                  "exceeds this (2 = equilateral; 0: off)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--max-edge-per-thickness", args->max_edge_per_thickness,
                  "coarsening keeps every coarse edge at most this many times the object's local "
                  "thickness at its ends (thin parts get flat slab tets otherwise; 0: off)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--shape-slack", args->shape_slack,
                  "relative slack of the coarsening's triangle-shape guard: a collapse may raise "
                  "its star's worst 2-D MIPS by this factor (lets needle strips such as CAD "
                  "cylinders coarsen; 0: strict)")
      ->check(CLI::Range(0.0, 0.99));
  sub->add_option("--thin-refine", args->thin_refine_ratio,
                  "before the shell, bisect input edges longer than this many times the object's "
                  "local thickness (same surface; where the input itself is too coarse for "
                  "--max-edge-per-thickness to help, e.g. a CAD plate; 0: off)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--shape-refine", args->shape_refine,
                  "before the shell, bisect the longest edge of input faces whose 2-D MIPS "
                  "exceeds 20 and whose longest edge exceeds this many eps (same surface; CAD "
                  "tessellations' needle and cap fans get vertices inside their faces; 0: off)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--shape-refine-spike-angle", args->shape_refine_spike_angle,
                  "the shape refinement leaves alone faces whose sharpest corner is a cone tip of "
                  "total face angle below DEG degrees (spike sides; default 90, 0: off)")
      ->check(CLI::Range(0.0, 360.0));
  sub->add_flag("--low-degree-slabs", args->low_degree_slabs,
                "slab nodes carry the patch's quadratic part at degree 2 and only the rest sheared "
                "(meshing/curved/README.md, step 7; off: the full shear)");
  sub->add_option("--curve-quality-floor", args->curve_quality_floor,
                  "faces whose slab tets have a sampled scaled Jacobian below Q after the curving "
                  "try a smaller blend (certified, within eps) that lifts them to Q (default 0: "
                  "off; measured mixed, meshing/curved/curved_mesher.hpp)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--curve-distortion-floor", args->curve_distortion_floor,
                  "faces whose curved patch has its smallest area element below D of its largest, "
                  "or folds, try a smaller blend (certified, within eps; default 0.1, 0: off)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--curved-min-area-ratio", args->curved_min_area_ratio,
                  "the curved-aware coarsening makes a face that needs full curving only if its "
                  "curved patch has its smallest area element at least R of its largest and does "
                  "not fold (default 0: off)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--shell-zoom-passes", args->shell_zoom_passes,
                  "thickness growth passes a coarsening round gives shell pillars pinned below "
                  "0.05 of their star's edges, each doubling them (default 1; 4 measured mixed: "
                  "benchmarks/results/robustness_zoom.md)")
      ->check(CLI::Range(1, 16));
  sub->add_option("--shell-pillar-cos", args->shell_pillar_cos,
                  "the coarse shell's distortion bound: each input face a coarse prism covers "
                  "makes at least this cosine with its pillars (default 0.01; 0: the bare "
                  "section condition)")
      ->check(CLI::Range(0.0, 0.5));
  sub->add_option("--shell-pillar-cos-relative", args->shell_pillar_cos_relative,
                  "where the input's own shell leans further than --shell-pillar-cos from an "
                  "input face (a knife edge), the bound there is this fraction of its cosine "
                  "(default 0.5; 0: the absolute bound everywhere)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_flag("--no-recurve", args->no_recurve,
                "keep the curving decided on the shell's slabs (no second try on the deeper slab "
                "layer)");
  sub->add_flag("--no-two-phase-coarsening", args->no_two_phase,
                "after a missed curved-aware attempt, coarsen the input again for the next one "
                "(default: coarsen it once under the linear bound and resume every later attempt "
                "from that shell)");
  sub->add_flag("--no-concurrent-linear-phase", args->no_concurrent_linear_phase,
                "run the two-phase coarsening's linear phase only once it is needed (default, on "
                "two or more threads: it starts beside the first attempt and is cancelled if not "
                "needed; the mesh is the same)");
  sub->add_flag("--no-embed-boundary", args->no_embed_boundary,
                "do not check the curved boundary for self-intersections while it is built (by "
                "default the curving of intersecting faces is lowered; the validator checks "
                "either way)");
  sub->add_flag("--exterior", args->exterior,
                "also mesh the space between the surface and a padded box (tags 3, 4)");
  sub->add_option("--padding", args->padding,
                  "exterior box padding, relative to the longest bbox edge (default 0.25)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--merge-short-edges", args->merge_short_edges,
                  "mesh the input with its edges shorter than L x the bbox's longest edge merged "
                  "(as `curvefem check --merge-short-edges`): the map is then to that surface, "
                  "saved as input_merged.obj with its vertex map")
      ->check(CLI::PositiveNumber);
  add_global_options(*sub, args->global);
  add_command(sub, [args]() {
    auto progress = apply_global_options(args->global);
    Stopwatch total;
    SurfaceMesh input = io::read_surface(args->input);
    check::CheckReport report = check::check_surface(input, {}, progress->callback());
    if (!report.acceptable)
      throw InputError(
          args->input + ": not a valid meshing input: " +
          (report.defects.empty() ? std::string("empty surface") : report.defects.front().message) +
          " (curvefem check " + args->input + " gives the full diagnosis)");
    // --merge-short-edges: the surface meshed (and mapped to) is the repaired one.
    std::optional<pipeline::MergedInput> merged;
    Eigen::MatrixXd original_V;  // --merge-short-edges: the input's vertices as read
    nlohmann::ordered_json input_repair = nullptr;
    if (args->merge_short_edges > 0) {
      merged = pipeline::merge_input(input, args->merge_short_edges, "--merge-short-edges",
                                     args->input, progress->callback());
      input_repair = nlohmann::ordered_json::parse(merged->summary.dump());
      input_repair["original"] = std::filesystem::absolute(args->input).string();
      input_repair["what"] =
          "the curved mesh maps to the repaired surface (input); an original vertex merged away "
          "is max_moved from its vertex there at most";
      original_V = input.V;
      input = std::move(merged->merge.mesh);  // the maps and pairs stay for the saved files
      report = std::move(merged->check);
    }
    for (const check::Defect& w : report.warnings)
      log::warn(args->input, ": ", w.kind, ": ", w.message);
    cv::CurvedMeshOptions options;
    options.order = args->order;
    options.eps_rel = args->eps;
    options.thickness_rel = args->thickness;
    options.thickness_per_edge = args->thickness_per_edge;
    options.threads = args->global.threads;
    options.deterministic = !args->nondeterministic;
    options.optimize.sweeps = args->optimize_sweeps;
    options.optimize.node_sweeps = args->optimize_node_sweeps;
    options.optimize.worst_sweeps = args->optimize_worst_sweeps;
    options.optimize.mean_sweeps = args->optimize_mean_sweeps;
    options.optimize.mean_variation_guard = !args->optimize_mean_free_nodes;
    options.optimize.worst_mips = args->optimize_worst_mips;
    options.optimize.worst_mips_sj_slack = args->optimize_worst_mips_sj_slack;
    options.optimize.node_energy = args->optimize_node_energy;
    options.optimize.edits.passes = args->optimize_edit_passes;
    options.optimize.edits.energy = args->optimize_edit_energy;
    options.optimize.edits.locked_mips = args->optimize_edit_locked_mips;
    options.optimize.edits.splits = args->optimize_edit_splits;
    options.optimize.edits.mean_flips = !args->optimize_no_mean_flips;
    options.exterior = args->exterior;
    options.recurve = !args->no_recurve;
    options.low_degree_slabs = args->low_degree_slabs;
    options.shell_pan = !args->no_pan;
    options.feature_chains = !args->no_feature_chains;
    options.curved_coarsening = !args->linear_coarsening;
    options.curved_repair = !args->no_curved_repair;
    options.two_phase = !args->no_two_phase;
    options.concurrent_linear_phase = !args->no_concurrent_linear_phase;
    options.embed_boundary = !args->no_embed_boundary;
    options.eps_samples = args->eps_samples;
    if (!args->constraints.empty())
      options.constraint_points = read_constraint_file(args->constraints);
    options.shell_split_mips = args->split_mips;
    options.max_edge_per_thickness = args->max_edge_per_thickness;
    options.thin_refine_ratio = args->thin_refine_ratio;
    options.shape_refine = args->shape_refine;
    options.shape_refine_spike_angle = args->shape_refine_spike_angle;
    options.shape_slack = args->shape_slack;
    options.curve_quality_floor = args->curve_quality_floor;
    options.curve_distortion_floor = args->curve_distortion_floor;
    options.curved_min_area_ratio = args->curved_min_area_ratio;
    options.shell_zoom_passes = args->shell_zoom_passes;
    options.shell_pillar_cos = args->shell_pillar_cos;
    options.shell_pillar_cos_relative = args->shell_pillar_cos_relative;
    options.exterior_padding = args->padding;
    std::string feature_source = "none";
    if (!args->features.empty()) {
      options.feature_edges = cv::validate_feature_edges(input, read_feature_file(args->features));
      feature_source = args->features;
      options.feature_min_size = 0;
      options.feature_end_trim = 0;
    } else if (!args->no_features) {
      options.feature_edges = cv::detect_feature_edges(input, args->feature_angle);
      feature_source = "dihedral angle > " + std::to_string(args->feature_angle) + " deg";
    }
    if (args->feature_min_size >= 0) options.feature_min_size = args->feature_min_size;
    if (args->feature_end_trim >= 0) options.feature_end_trim = args->feature_end_trim;
    // One level (--eps) or several (--eps-levels) from one shell and one coarsening.
    const std::vector<double> eps_values =
        args->eps_levels.empty() ? std::vector<double>{args->eps} : args->eps_levels;
    std::map<std::string, double> eps_by_tag;
    for (const std::string& entry : args->eps_by_tag) {
      const auto eq = entry.find('=');
      char* end = nullptr;
      const double value =
          eq == std::string::npos ? 0.0 : std::strtod(entry.c_str() + eq + 1, &end);
      if (eq == std::string::npos || eq == 0 || end == entry.c_str() + eq + 1 || *end != '\0')
        throw InputError("--eps-by-tag: '" + entry + "' is not TAG=EPS");
      eps_by_tag[entry.substr(0, eq)] = value;
    }
    std::vector<cv::EpsLevel> levels;
    for (double e : eps_values) {
      std::vector<double> scale;
      if (!args->eps_field.empty())
        scale = pipeline::eps_scale_from_expression(input, args->eps_field, e, "--eps-field");
      levels.push_back({e, pipeline::min_eps_scale(
                               std::move(scale), pipeline::eps_scale_from_tags(input, eps_by_tag, e,
                                                                               "--eps-by-tag"))});
    }
    std::vector<cv::CurvedMeshStats> level_stats;
    const std::vector<cv::CurvedMesh> results =
        cv::build_curved_mesh_levels(input, options, levels, level_stats, progress->callback());
    const bool several = levels.size() > 1;
    StagedOutputDir out(args->output);
    std::string input_abs = std::filesystem::absolute(args->input).string();
    std::string input_checksum = pipeline::file_checksum(args->input);
    if (merged) {  // the repaired surface is the input the saved map refers to
      io::write_surface(out.path("input_merged.obj"), input, io::SurfaceFormat::obj);
      input_checksum = pipeline::file_checksum(out.path("input_merged.obj"));
      input_abs = std::filesystem::absolute(out.final_path("input_merged.obj")).string();
      nlohmann::json map = pipeline::merge_map_json(merged->merge);
      map["input"] = input_repair["original"];
      map["output"] = input_abs;
      write_text_file_atomic(out.path("input_merged_vertex_map.json"), map.dump(1) + "\n");
      input_repair["surface"] = input_abs;
      input_repair["vertex_map"] =
          std::filesystem::absolute(out.final_path("input_merged_vertex_map.json")).string();
    }
    bool all_ok = true;
    std::vector<std::string> defects;  // printed to stderr at the end
    nlohmann::ordered_json level_list = nlohmann::ordered_json::array();
    std::vector<std::string> lines;
    for (std::size_t i = 0; i < levels.size(); ++i) {
      const double eps = levels[i].eps_rel;
      const cv::CurvedMesh& result = results[i];
      const cv::CurvedMeshStats& stats = level_stats[i];
      cv::CurvedMeshOptions level_options = options;
      level_options.eps_rel = eps;
      level_options.eps_scale = levels[i].eps_scale;
      char name[64];
      std::snprintf(name, sizeof name, "eps_%g", eps);
      const std::string prefix = several ? std::string(name) + "/" : std::string();
      if (several) std::filesystem::create_directories(out.path(name));
      Stopwatch level_watch;
      const cv::CurvedValidation check = cv::validate_curved_mesh(result.mesh, result.map, input);
      Stopwatch roundtrip_watch;
      const ShellFibers fibers = meshing::shell::fibers_of(result.shell, input);
      const pipeline::MapRoundtrip trip = pipeline::map_roundtrip(result.map, fibers, input);
      const double roundtrip = trip.max_error_rel;
      const int roundtrip_failures = trip.failures;
      const double roundtrip_seconds = roundtrip_watch.seconds();
      const bool ok = pipeline::curved_mesh_valid(check, eps, trip);
      all_ok = all_ok && ok;
      for (const std::string& defect : pipeline::curved_mesh_defects(check, eps, trip))
        defects.push_back(prefix + "mesh: not valid: " + defect + "\n");

      Stopwatch write;
      MeshFields quality;
      quality.cell_data = curved_validation_cell_fields(check);
      io::write_vtu(out.path(prefix + "mesh.vtu"), result.mesh, quality);
      io::write_msh(out.path(prefix + "mesh.msh"), result.mesh);
      io::write_boundary_map(out.path(prefix + "boundary_map.json"), result.map, input_abs, &fibers,
                             input_checksum);
      nlohmann::ordered_json stages = nlohmann::ordered_json::object();
      double meshing_seconds = 0;
      for (const auto& [stage, t] : stats.stage_seconds) {
        stages[stage] = t;
        meshing_seconds += t;
      }
      stages["validate"] = check.seconds;
      stages["map roundtrip"] = roundtrip_seconds;
      stages["write"] = write.seconds();
      const pipeline::InputFloors floors = pipeline::input_floors(
          input, result.map, result.mesh, check.cell_mips, check.cell_scaled_jacobian);
      if (const std::string hint = pipeline::merge_hint(floors, eps); !hint.empty())
        log::warn(prefix, "mesh: ", hint);
      nlohmann::ordered_json j = {
          {"input", input_abs},
          {"input_repair",
           !merged ? input_repair : [&] {
             nlohmann::ordered_json r = input_repair;
             r["original_distance"] = nlohmann::ordered_json::parse(
                 pipeline::original_distance_json(original_V, merged->merge.vertex_map, result.map, eps)
                     .dump());
             return r;
           }()},
          {"input_warnings",
           nlohmann::ordered_json::parse(pipeline::defects_json(report.warnings).dump())},
          {"features", feature_source},
          {"eps_field", args->eps_field.empty() ? nlohmann::ordered_json(nullptr)
                                                : nlohmann::ordered_json(args->eps_field)},
          {"eps_by_tag", eps_by_tag.empty() ? nlohmann::ordered_json(nullptr)
                                            : nlohmann::ordered_json(eps_by_tag)},
          {"eps_levels",
           several ? nlohmann::ordered_json(eps_values) : nlohmann::ordered_json(nullptr)}};
      j.update(pipeline::curved_mesh_stats_json(stats, level_options));
      j.update(nlohmann::ordered_json{
          {"output_tets", result.mesh.num_cells()},
          {"output_nodes", result.mesh.num_nodes()},
          {"output_boundary_faces", result.map.boundary.num_cells()},
          {"exterior", args->exterior},
          {"exterior_padding_rel", args->exterior ? nlohmann::ordered_json(args->padding)
                                                  : nlohmann::ordered_json(nullptr)},
          {"exterior_box",
           args->exterior
               ? nlohmann::ordered_json::array({{stats.exterior_box_lo[0], stats.exterior_box_lo[1],
                                                 stats.exterior_box_lo[2]},
                                                {stats.exterior_box_hi[0], stats.exterior_box_hi[1],
                                                 stats.exterior_box_hi[2]}})
               : nlohmann::ordered_json(nullptr)},
          {"max_distance_rel", check.max_distance_rel},
          {"distance_points", stats.distance_points},
          {"distance_points_max_distance_rel", check.points_max_distance_rel},
          {"min_jacobian_certified", check.certified()},
          {"min_scaled_jacobian", check.min_scaled_jacobian},
          {"boundary_self_intersections", check.boundary_self_intersections},
          {"map_roundtrip_max_error_rel", roundtrip},
          {"map_roundtrip_failures", roundtrip_failures},
          {"map_roundtrip_worst_vertex", trip.worst_vertex},
          {"map_roundtrip_first_failure", trip.first_failure},
          {"map_roundtrip_method",
           "every input vertex v: phi(v) located on the curved boundary from its position, "
           "pulled back along the shell fibers saved in boundary_map.json (the shell projection "
           "at h = 0); |v - phi^-1(phi(v))| / bbox edge; valid needs <= 1e-6"},
          {"bijectivity_evidence",
           "certified positive tets + intersection-free subdivided boundary + unfolded input "
           "triangles within each boundary face; the shell's section property is reported in "
           "shell_section_verified"},
          {"validation", curved_validation_json(check, eps)},
          {"input_floors",
           nlohmann::ordered_json::parse(pipeline::input_floors_json(floors).dump())},
          {"valid", ok},
          {"threads", args->global.threads},
          {"deterministic", !args->nondeterministic},
          {"time_s", stages},
          {"peak_rss_mb", peak_rss_mb()}});
      // One level: the whole command; several: this level's meshing, validation and output.
      j["time_s"]["total"] = several ? meshing_seconds + level_watch.seconds() : total.seconds();
      write_text_file_atomic(out.path(prefix + "report.json"), j.dump(2) + "\n");
      if (several) {
        auto stage = [&](const std::string& key) {
          for (const auto& [k, t] : stats.stage_seconds)
            if (k == key) return t;
          return 0.0;
        };
        level_list.push_back({{"eps_rel", eps},
                              {"dir", name},
                              {"valid", ok},
                              {"coarse_faces", stats.coarse_faces},
                              {"coarsen_start_faces", stats.coarsen_start_faces},
                              {"output_tets", result.mesh.num_cells()},
                              {"output_nodes", result.mesh.num_nodes()},
                              {"max_distance_rel", check.max_distance_rel},
                              {"min_scaled_jacobian", check.min_scaled_jacobian},
                              {"shell_seconds", stage("shell")},
                              {"coarsen_seconds", stage("coarsen")},
                              {"meshing_seconds", meshing_seconds},
                              {"seconds", j["time_s"]["total"]}});
      }
      char distance[160];
      if (levels[i].eps_scale.empty())
        std::snprintf(distance, sizeof distance, "max distance %.3g (eps %.3g)",
                      check.max_distance_rel, eps);
      else
        std::snprintf(
            distance, sizeof distance,
            "max distance %.3g, at most %.3g of the local eps (eps field up to %.3g)",
            check.max_distance_rel,
            std::max(check.max_scaled_distance_rel, check.points_max_scaled_distance_rel) / eps,
            eps);
      char line[512];
      std::snprintf(line, sizeof line,
                    "mesh: %d tets of order %d (%d slab, %d interior), %d boundary faces from %d "
                    "input faces; certified %s, boundary embedded %s, %s; %.1f s; %s\n",
                    result.mesh.num_cells(), args->order, stats.slab_tets, stats.interior_tets,
                    result.map.boundary.num_cells(), stats.input_faces,
                    check.certified() ? "yes" : "NO", check.boundary_ok() ? "yes" : "NO", distance,
                    j["time_s"]["total"].get<double>(),
                    out.final_path(prefix + "report.json").string().c_str());
      lines.push_back(line);
    }
    if (several)
      write_text_file_atomic(out.path("levels.json"),
                             nlohmann::ordered_json{{"input", input_abs},
                                                    {"order", args->order},
                                                    {"levels", level_list},
                                                    {"valid", all_ok},
                                                    {"seconds", total.seconds()}}
                                     .dump(2) +
                                 "\n");
    out.commit();
    progress.reset();
    for (const std::string& line : lines) std::fputs(line.c_str(), stdout);
    for (const std::string& line : defects) std::fputs(line.c_str(), stderr);
    if (several) std::printf("mesh: %zu eps levels in %.1f s\n", levels.size(), total.seconds());
    std::fflush(stdout);
    return all_ok ? 0 : 3;
  });
}

}  // namespace curvefem::cli
