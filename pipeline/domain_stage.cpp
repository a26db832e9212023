// Stages load_surface and mesh_domain (stages.hpp).
#include <algorithm>
#include <fstream>
#include <optional>
#include <tuple>

#include "mapping/boundary_inverse.hpp"
#include "mapping/selection.hpp"
#include "meshing/check/check_surface.hpp"
#include "meshing/check/merge_short_edges.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/curved/curved_mesher.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/curved/features.hpp"
#include "meshing/io/cad_part.hpp"
#include "meshing/io/msh_io.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "meshing/shell/fibers_of.hpp"
#include "meshing/shell/shell_intersection.hpp"
#include "meshing/tetfill/tetfill.hpp"
#include "pipeline/eps_field.hpp"
#include "pipeline/mesh_dir.hpp"
#include "pipeline/mesh_validity.hpp"
#include "pipeline/report_json.hpp"
#include "pipeline/stages.hpp"

namespace curvefem::pipeline {
namespace {
namespace cv = meshing::curved;
using json = nlohmann::json;

/// Fails early (before meshing) when a selection covers no point of the input surface.
void check_selection_on_input(const Selection& s, const SurfaceMesh& input,
                              const std::string& file) {
  for (int f = 0; f < input.num_faces(); ++f)
    if (mapping::face_coverage(s, input, f) > 0) return;
  throw InputError(s.where +
                       ": selects nothing on the input surface (no corner or centroid of an "
                       "input face is selected)",
                   {.file = file});
}

LagrangeMesh load_mesh_file(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw IoError("mesh file not found", {.file = path.string()});
  const std::string ext = path.extension().string();
  LagrangeMesh mesh;
  if (ext == ".vtu")
    mesh = io::read_vtu(path).mesh;
  else if (ext == ".msh")
    mesh = io::read_msh(path);
  else
    throw InputError("mesh must be .msh or .vtu", {.file = path.string()});
  if (mesh.kind != CellKind::tetrahedron)
    throw InputError("mesh holds no tetrahedra", {.file = path.string()});
  return mesh;
}

/// The cells of `mesh` tagged in `tags`, with the nodes they use (renumbered in order);
/// `old_to_new` gets, for every node of `mesh`, its new id or -1.
LagrangeMesh extract_cells(const LagrangeMesh& mesh, std::initializer_list<int> tags,
                           std::vector<int>& old_to_new) {
  CF_VERIFY(mesh.cell_tags.size() == mesh.num_cells(), "extract_cells: the mesh has no cell tags");
  std::vector<int> kept;
  for (int c = 0; c < mesh.num_cells(); ++c)
    if (std::find(tags.begin(), tags.end(), mesh.cell_tags[c]) != tags.end()) kept.push_back(c);
  old_to_new.assign(std::size_t(mesh.num_nodes()), -1);
  int n = 0;
  for (int c : kept)
    for (int j = 0; j < mesh.cells.cols(); ++j)
      if (old_to_new[std::size_t(mesh.cells(c, j))] < 0)
        old_to_new[std::size_t(mesh.cells(c, j))] = n++;
  LagrangeMesh out;
  out.kind = mesh.kind;
  out.order = mesh.order;
  out.nodes.resize(n, 3);
  for (int v = 0; v < mesh.num_nodes(); ++v)
    if (old_to_new[std::size_t(v)] >= 0)
      out.nodes.row(old_to_new[std::size_t(v)]) = mesh.nodes.row(v);
  out.cells.resize(Eigen::Index(kept.size()), mesh.cells.cols());
  out.cell_tags.resize(Eigen::Index(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i) {
    for (int j = 0; j < mesh.cells.cols(); ++j)
      out.cells(Eigen::Index(i), j) = old_to_new[std::size_t(mesh.cells(kept[i], j))];
    out.cell_tags[Eigen::Index(i)] = mesh.cell_tags[kept[i]];
  }
  return out;
}

/// Sets the outer box of an exterior run from the mesh's bounding box.
void set_outer_box(Domain& d, double padding) {
  OuterBox box;
  std::tie(box.lo, box.hi) = vertex_bounding_box(d.mesh);
  box.tol = 1e-9 * (box.hi - box.lo).norm();
  d.report["exterior"] = {
      {"padding", padding},
      {"box", {{box.lo[0], box.lo[1], box.lo[2]}, {box.hi[0], box.hi[1], box.hi[2]}}},
      {"tets", d.mesh.num_cells()}};
  d.outer_box = box;
}

cv::CurvedMeshOptions curved_options(const CaseSpec& spec, const StageContext& ctx,
                                     const SurfaceMesh& input) {
  cv::CurvedMeshOptions options;
  options.order = spec.order;
  options.eps_rel = spec.eps;
  options.thickness_rel = spec.thickness;
  options.thickness_per_edge = spec.thickness_per_edge;
  options.eps_samples = spec.eps_samples;
  options.feature_chains = spec.feature_chains;
  options.curved_coarsening = spec.curved_coarsening;
  options.threads = ctx.threads;
  options.deterministic = spec.deterministic;
  options.feature_edges = case_feature_edges(spec, input);
  if (spec.features == FeatureMode::file) {  // the user's own list
    options.feature_min_size = 0;
    options.feature_end_trim = 0;
  }
  options.exterior = spec.exterior;
  options.exterior_padding = spec.padding;
  return options;
}

std::vector<double> eps_scale_at(const CaseSpec& spec, const SurfaceMesh& input, double eps) {
  std::vector<double> scale;
  if (!spec.eps_field.empty())
    scale = eps_scale_from_expression(input, spec.eps_field, eps, "/meshing/eps_field");
  return min_eps_scale(std::move(scale),
                       eps_scale_from_tags(input, spec.eps_by_tag, eps, "/meshing/eps_by_tag"));
}

// A curved mesh made at bound `eps` into `d` (whose input is set): fibers, report, validation,
// and the exterior's sub-domain.
void finish_curved(const CaseSpec& spec, const StageContext& ctx, Domain& d, cv::CurvedMesh curved,
                   const cv::CurvedMeshStats& stats, const cv::CurvedMeshOptions& options) {
  d.mesh = std::move(curved.mesh);
  d.curved_map = std::move(curved.map);
  d.fibers = std::make_shared<const ShellFibers>(meshing::shell::fibers_of(curved.shell, d.input));
  json stages = json::object();
  for (const auto& [name, sec] : stats.stage_seconds) stages[name] = sec;
  d.report.update(json::parse(pipeline::curved_mesh_stats_json(stats, options).dump()));
  d.report["stage_s"] = stages;
  if (spec.validate) {
    ctx.update("validate mesh", 0.0);
    validate_domain(d, options.eps_rel);
  }
  if (spec.exterior && spec.solve_on != SolveOn::both) {
    // The domain is the outside: the outer slab layer and the exterior (tags 3, 4; the whole
    // mesh was validated above). The map's triangles are faces of outer slab tets too.
    std::vector<int> old_to_new;
    d.mesh = extract_cells(d.mesh, {3, 4}, old_to_new);
    Eigen::VectorXi& to_volume = d.curved_map->boundary_node_to_volume;
    for (Eigen::Index i = 0; i < to_volume.size(); ++i)
      if (to_volume[i] >= 0) {
        to_volume[i] = old_to_new[std::size_t(to_volume[i])];
        if (to_volume[i] < 0)
          throw MeshingError("exterior: a node of the curved surface is in no outer tet");
      }
  }
  // solve_on both: the whole box; the curved surface is an interface (its triangles are faces
  // of a slab tet and of an outer slab tet), the box the only boundary.
  if (spec.exterior) set_outer_box(d, spec.padding);
}

void mesh_curved(const CaseSpec& spec, const StageContext& ctx, Domain& d) {
  cv::CurvedMeshOptions options = curved_options(spec, ctx, d.input);
  options.eps_scale = eps_scale_at(spec, d.input, spec.eps);
  cv::CurvedMeshStats stats;
  cv::CurvedMesh curved = cv::build_curved_mesh(d.input, options, stats, ctx.progress);
  finish_curved(spec, ctx, d, std::move(curved), stats, options);
}

void mesh_dense(const CaseSpec& spec, const StageContext& ctx, Domain& d) {
  ctx.update("tetrahedralize input", 0.0);
  meshing::tetfill::TetFillOptions options;
  options.threads = std::max(ctx.threads, 1);
  meshing::tetfill::TetFillResult fill;
  const SurfaceMesh& input = d.input;
  int inside_tets = 0;  // exterior, solve_on both: the first tets are the inside's
  if (!spec.exterior) {
    fill = meshing::tetfill::fill_interior(input.V, input.F, options);
  } else {
    // Outside the input, inside its bounding box padded as the curved mesher pads it: the
    // input enters reversed, as the box's cavity; its vertices stay first (φ = identity).
    const auto [lo, hi] = padded_bounding_box(input.V, spec.padding);
    const SurfaceMesh box = make_box(lo, hi, 4);
    const int nv = input.num_vertices();
    Eigen::MatrixXd V(nv + box.num_vertices(), 3);
    V << input.V, box.V;
    Eigen::MatrixXi F(input.num_faces() + box.num_faces(), 3);
    F.topRows(input.num_faces()) = input.F.rowwise().reverse();
    F.bottomRows(box.num_faces()) = box.F.array() + nv;
    fill = meshing::tetfill::fill_interior(V, F, options);
    if (spec.solve_on == SolveOn::both) {
      // The inside too, sharing the input's vertices (both fills keep them first and keep the
      // input's triangles): its other vertices go after the outside's, its tets first.
      const meshing::tetfill::TetFillResult inside =
          meshing::tetfill::fill_interior(input.V, input.F, options);
      const Eigen::Index n_out = fill.V.rows(), extra = inside.V.rows() - nv;
      fill.V.conservativeResize(n_out + extra, 3);
      fill.V.bottomRows(extra) = inside.V.bottomRows(extra);
      Eigen::MatrixXi T(inside.T.rows() + fill.T.rows(), 4);
      for (Eigen::Index t = 0; t < inside.T.rows(); ++t)
        for (int j = 0; j < 4; ++j)
          T(t, j) = inside.T(t, j) < nv ? inside.T(t, j) : int(n_out) + inside.T(t, j) - nv;
      T.bottomRows(fill.T.rows()) = fill.T;
      inside_tets = int(inside.T.rows());
      fill.T = T;
    }
  }
  d.mesh = LagrangeMesh{};
  d.mesh.kind = CellKind::tetrahedron;
  d.mesh.order = 1;
  d.mesh.nodes = fill.V;
  d.mesh.cells = fill.T;
  if (spec.exterior) {
    d.mesh.cell_tags = Eigen::VectorXi::Constant(d.mesh.num_cells(), 4);
    d.mesh.cell_tags.head(inside_tets).setConstant(2);
    set_outer_box(d, spec.padding);
  }
  d.identity_map = mapping::make_identity_boundary_map(input);
  d.report["interior_vertices"] = fill.V.rows() - fill.boundary_vertices;
  d.report["tetfill_s"] = fill.seconds;
}

}  // namespace

int OuterBox::side(const Eigen::Vector3d& x) const { return mapping::box_side_of(x, lo, hi, tol); }

MergedInput merge_input(const SurfaceMesh& input, double length_rel, const std::string& where,
                        const std::string& file, const ProgressFn& progress) {
  MergedInput out;
  const double length = length_rel * bbox_longest_edge(input.V);
  out.merge = check::merge_short_edges(input, {.max_length = length});
  out.check = check::check_surface(out.merge.mesh, {}, progress);
  if (!out.check.acceptable)
    throw InputError(where +
                         ": the surface with its short edges merged is not a valid meshing "
                         "input: " +
                         (out.check.defects.empty() ? std::string("empty surface")
                                                    : out.check.defects.front().message),
                     {.file = file});
  out.summary = merge_summary_json(out.merge, length_rel, length);
  log::info("merged ", out.merge.merged.size(), " edges shorter than ", length_rel,
            " x the bbox (longest ", out.merge.max_moved, ", ", out.merge.refused,
            " left); the repaired surface is meshed");
  return out;
}

nlohmann::json original_distance_json(const Eigen::MatrixXd& V, const std::vector<int>& vertex_map,
                                      const BoundaryMap& map, double eps_rel) {
  double worst = 0;
  int at = -1;
  for (int v = 0; v < int(V.rows()) && v < int(vertex_map.size()); ++v) {
    const int w = vertex_map[std::size_t(v)];
    if (w < 0 || w >= map.vertex_face.size() || map.vertex_face(w) < 0) continue;
    const double d = (V.row(v).transpose() - map.image(w)).norm();
    if (d > worst || at < 0) worst = d, at = v;
  }
  const double box = bbox_longest_edge(V);
  const double rel = box > 0 ? worst / box : 0.0;
  return {{"max_distance_rel", rel},
          {"vertex", at},
          {"within_eps", rel <= eps_rel},
          {"what",
           "|v - phi(its repaired vertex)| over the input as read (merged-away vertices "
           "from their replacement's image)"}};
}

SurfaceMesh load_surface(const CaseSpec& spec, const StageContext& ctx, nlohmann::json* warnings,
                         InputRepair* repair) {
  if (!spec.mesh_dir.empty()) return {};  // the input is the saved mesh's (mesh_domain)
  std::optional<ScopedTimer> t;
  if (ctx.timings) t.emplace(*ctx.timings, "load_surface");
  ctx.update("load surface", 0.0);
  SurfaceMesh input;
  if (spec.builtin_surface == BuiltinSurface::sphere)
    input = make_icosphere(spec.sphere_level, spec.radius);
  else if (spec.builtin_surface == BuiltinSurface::torus)
    input = make_torus(spec.torus_R, spec.torus_r, spec.torus_nu, spec.torus_nv);
  else if (spec.builtin_surface == BuiltinSurface::box)
    input = make_box(spec.box_lo, spec.box_hi, spec.box_divisions);
  else
    input = io::read_surface(spec.surface);
  const std::string where = (spec.builtin_surface == BuiltinSurface::none)
                                ? "/geometry/surface"
                                : "/geometry/builtin_surface";
  check::CheckReport report = check::check_surface(input, {});
  if (!report.acceptable)
    throw InputError(where + ": not a valid meshing input: " +
                         (report.defects.empty() ? std::string("empty surface")
                                                 : report.defects.front().message) +
                         (spec.surface.empty() ? std::string()
                                               : " (curvefem check " + spec.surface.string() +
                                                     " gives the full diagnosis)"),
                     {.file = spec.case_file.string()});
  if (spec.merge_short_edges > 0) {  // the repaired surface is meshed and mapped to
    MergedInput merged = merge_input(input, spec.merge_short_edges, "/meshing/merge_short_edges",
                                     spec.case_file.string());
    if (repair) {
      repair->original = input;
      repair->vertex_map = merged.merge.vertex_map;
      repair->face_origin = merged.merge.face_origin;
      repair->report = merged.summary;
      repair->report["input_vertices"] = input.num_vertices();
      repair->report["input_faces"] = input.num_faces();
      repair->report["what"] =
          "the mesh maps to the repaired surface (surface.vtu, input.msh); an input vertex "
          "merged away is max_moved from its vertex there at most; surface_input.vtu: the "
          "solution on the input as read, each merged-away vertex with its vertex's values";
    }
    input = std::move(merged.merge.mesh);
    report = std::move(merged.check);
  }
  for (const check::Defect& w : report.warnings) log::warn(where, ": ", w.kind, ": ", w.message);
  if (warnings) *warnings = defects_json(report.warnings);
  for (const LoadCase& load : spec.loads())
    for (const auto& bc : load.boundary_conditions)
      if (!mapping::uses_outer_box(bc.select))  // may select the box only: checked on the mesh
        check_selection_on_input(bc.select, input, spec.case_file.string());
  return input;
}

std::vector<std::array<int, 2>> case_feature_edges(const CaseSpec& spec, const SurfaceMesh& input) {
  if (spec.features == FeatureMode::none) return {};
  if (spec.features != FeatureMode::file)
    return cv::detect_feature_edges(
        input, spec.features == FeatureMode::angle ? spec.feature_angle : 60.0);
  const std::string where = "/geometry/features/file";
  std::ifstream f(spec.feature_file);
  if (!f) throw InputError(where + ": cannot open " + spec.feature_file.string());
  std::vector<std::array<int, 2>> edges;
  try {
    const json j = json::parse(f);
    const json& list = j.is_object() ? j.at("edges") : j;
    for (std::size_t i = 0; i < list.size(); ++i) {
      if (!list[i].is_array() || list[i].size() != 2)
        throw InputError(where + ": feature edge " + std::to_string(i) +
                         " is not a pair of vertex ids");
      edges.push_back({list[i][0].get<int>(), list[i][1].get<int>()});
    }
  } catch (const json::exception& e) {
    throw InputError(where + ": not a JSON list of vertex-index pairs: " + e.what());
  }
  try {
    return cv::validate_feature_edges(input, edges);
  } catch (const InputError& e) {
    throw InputError(where + ": " + e.what());
  }
}

Domain mesh_domain(const CaseSpec& spec, SurfaceMesh input, const StageContext& ctx) {
  Domain d;
  d.method = spec.method;
  if (!spec.dense_surface()) {
    std::optional<ScopedTimer> t;
    if (ctx.timings) t.emplace(*ctx.timings, "load_mesh");
    ctx.update("load mesh", 0.0);
    if (spec.builtin == BuiltinVolume::ball)
      d.mesh = io::make_ball_mesh(1.0, spec.builtin_size, spec.builtin_order);
    else if (spec.builtin == BuiltinVolume::cube)
      d.mesh = elevate_order(make_cube_tets(spec.builtin_divisions), spec.builtin_order,
                             [](const Eigen::Vector3d& x) { return x; });
    else
      d.mesh = load_mesh_file(spec.mesh);
    if (!spec.data_surface.empty()) {
      const SurfaceMesh data = io::read_surface(spec.data_surface);
      if (data.num_faces() == 0)
        throw InputError(spec.data_surface.string() + ": no triangles (geometry.data_surface)");
      d.data_surface = std::make_shared<const meshing::shell::InputSurfaceIndex>(data.V, data.F);
      d.report["data_surface"] = {{"file", spec.data_surface.string()},
                                  {"faces", data.num_faces()},
                                  {"boundary_values_at", "the closest point of the surface"}};
    }
    return d;
  }
  if (!spec.mesh_dir.empty()) {
    d = load_mesh_dir(spec, ctx);
    for (const LoadCase& load : spec.loads())
      for (const auto& bc : load.boundary_conditions)
        check_selection_on_input(bc.select, d.input, spec.case_file.string());
    return d;
  }
  d.input = std::move(input);
  d.report["input_vertices"] = d.input.num_vertices();
  d.report["input_faces"] = d.input.num_faces();
  std::optional<ScopedTimer> t;
  if (ctx.timings) t.emplace(*ctx.timings, "meshing");
  if (spec.method == MeshingMethod::curved)
    mesh_curved(spec, ctx, d);
  else
    mesh_dense(spec, ctx, d);
  return d;
}

std::vector<Domain> mesh_domain_levels(const CaseSpec& spec, SurfaceMesh input,
                                       const StageContext& ctx) {
  if (spec.method != MeshingMethod::curved || spec.eps_levels.empty() || !spec.mesh_dir.empty())
    throw InputError("mesh levels: a curved case with meshing.eps a list of bounds");
  std::optional<ScopedTimer> t;
  if (ctx.timings) t.emplace(*ctx.timings, "meshing");
  const cv::CurvedMeshOptions options = curved_options(spec, ctx, input);
  std::vector<cv::EpsLevel> levels;
  for (double e : spec.eps_levels) levels.push_back({e, eps_scale_at(spec, input, e)});
  std::vector<cv::CurvedMeshStats> stats;
  std::vector<cv::CurvedMesh> meshes =
      cv::build_curved_mesh_levels(input, options, levels, stats, ctx.progress);
  std::vector<Domain> out(levels.size());
  for (std::size_t i = 0; i < levels.size(); ++i) {
    Domain& d = out[i];
    d.method = spec.method;
    d.input = input;
    d.report["input_vertices"] = d.input.num_vertices();
    d.report["input_faces"] = d.input.num_faces();
    cv::CurvedMeshOptions o = options;
    o.eps_rel = levels[i].eps_rel;
    o.eps_scale = levels[i].eps_scale;
    finish_curved(spec, ctx, d, std::move(meshes[i]), stats[i], o);
  }
  return out;
}

}  // namespace curvefem::pipeline
