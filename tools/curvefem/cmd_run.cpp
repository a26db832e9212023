// `curvefem run CASE.json [-o DIR]`: the whole pipeline of DESIGN.md §1.
//   meshing.method "curved": dense surface → coarse curved tet mesh of order k with the boundary
//   map
//     φ (meshing/curved); boundary conditions painted on the dense input are evaluated at φ⁻¹(x)
//     (mapping/); the solution is read at φ(v) for every input vertex.
//   meshing.method "dense": the classical baseline — the input itself is tetrahedralized (tetfill,
//     boundary unchanged, φ = identity), same physics, same outputs.
//   meshing.method "given": p-FEM on a given curved tet mesh (boundary data on the mesh).
// Writes volume.vtu (Lagrange cells of order max(p, k) with the solution), surface.vtu (the dense
// input with the solution, exact solution, error and selection coverage; dense-surface methods),
// result.pvd, resolved_case.json, open_in_paraview.py (--paraview) and report.json (last). Nothing
// is written before the solve succeeds; a failed run leaves no output directory it created.
// The pipeline itself (run_case, run_case.hpp) is shared with `curvefem study`.
#include <algorithm>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <tuple>
#include <unordered_map>

#include "fem/assembly/face_integration.hpp"
#include "fem/problems/constraints.hpp"
#include "fem/problems/elasticity.hpp"
#include "fem/problems/error_norms.hpp"
#include "fem/problems/interpolation.hpp"
#include "fem/problems/null_space.hpp"
#include "fem/problems/poisson.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "fem/space/function_space.hpp"
#include "mapping/boundary_inverse.hpp"
#include "mapping/selection.hpp"
#include "mapping/surface_transfer.hpp"
#include "meshing/check/check_surface.hpp"
#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/geometry_degree.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/curved/curved_mesher.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/curved/features.hpp"
#include "meshing/curved/jacobian_certificate.hpp"
#include "meshing/io/cad_part.hpp"
#include "meshing/io/msh_io.hpp"
#include "meshing/io/pvd.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/vtu_io.hpp"
#include "meshing/tetfill/tetfill.hpp"
#include "tools/curvefem/case_file.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"
#include "tools/curvefem/paraview_script.hpp"
#include "tools/curvefem/report_json.hpp"
#include "tools/curvefem/run_case.hpp"

namespace curvefem::cli {

// cmd_mesh.cpp
nlohmann::ordered_json curved_validation_json(const meshing::curved::CurvedValidation& v,
                                              double eps_rel);
nlohmann::ordered_json optimize_json(const meshing::curved::OptimizeStats& s);
std::vector<Field> curved_validation_cell_fields(const meshing::curved::CurvedValidation& v);

namespace {
namespace cv = meshing::curved;

using json = nlohmann::json;

struct RunOptions {
  GlobalOptions global;
  std::string case_file;
  std::string output;
  bool paraview = false;
};

LagrangeMesh load_mesh(const std::filesystem::path& path) {
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

struct PositionKey {
  std::array<std::uint64_t, 3> bits;
  bool operator==(const PositionKey&) const = default;
};
struct PositionHash {
  std::size_t operator()(const PositionKey& k) const {
    return k.bits[0] * 0x9E3779B97F4A7C15ull ^ (k.bits[1] + 0x7F4A7C15ull) * 31 ^ k.bits[2];
  }
};
PositionKey key_of(const Eigen::Vector3d& p) {
  PositionKey k;
  for (int i = 0; i < 3; ++i) std::memcpy(&k.bits[i], &p[i], sizeof(double));
  return k;
}

/// Physical tag of every boundary face, from the triangles stored in the mesh file (-1 if none).
std::vector<int> boundary_face_tags(const std::filesystem::path& path, const LagrangeMesh& mesh,
                                    const fem::FunctionSpace& space) {
  std::vector<int> tags(space.boundary_faces.size(), -1);
  if (path.extension() != ".msh") return tags;
  SurfaceMesh triangles;
  try {
    triangles = io::read_msh_boundary_triangles(path);  // any order; corners + physical tags
  } catch (const InputError&) {
    return tags;  // no triangles in the file
  }
  if (!triangles.has_tags()) return tags;
  std::unordered_map<PositionKey, int, PositionHash> node_of;
  for (int n = 0; n < mesh.num_nodes(); ++n)
    node_of.emplace(key_of(mesh.nodes.row(n).transpose()), n);
  std::map<std::array<int, 3>, int> tag_of;
  for (int f = 0; f < triangles.num_faces(); ++f) {
    std::array<int, 3> ids;
    bool found = true;
    for (int c = 0; c < 3; ++c) {
      auto it = node_of.find(key_of(triangles.V.row(triangles.F(f, c)).transpose()));
      if (it == node_of.end())
        found = false;
      else
        ids[c] = it->second;
    }
    if (!found) continue;
    std::sort(ids.begin(), ids.end());
    tag_of[ids] = triangles.tags[f];
  }
  for (std::size_t f = 0; f < space.boundary_faces.size(); ++f) {
    const auto [cell, j] = space.boundary_faces[f];
    std::array<int, 3> ids;
    int k = 0;
    for (int i = 0; i < 4; ++i)
      if (i != j) ids[k++] = mesh.cells(cell, i);
    std::sort(ids.begin(), ids.end());
    auto it = tag_of.find(ids);
    if (it != tag_of.end()) tags[f] = it->second;
  }
  return tags;
}

/// Sides of the built-in unit cube: 1..6 = x=0, x=1, y=0, y=1, z=0, z=1 (as make_box).
std::vector<int> cube_face_tags(const LagrangeMesh& mesh, const fem::FunctionSpace& space) {
  std::vector<int> tags(space.boundary_faces.size(), -1);
  for (std::size_t f = 0; f < tags.size(); ++f) {
    const auto [cell, j] = space.boundary_faces[f];
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(2), hi = Eigen::Vector3d::Constant(-1);
    for (int i = 0; i < 4; ++i)
      if (i != j) {
        lo = lo.cwiseMin(mesh.nodes.row(mesh.cells(cell, i)).transpose());
        hi = hi.cwiseMax(mesh.nodes.row(mesh.cells(cell, i)).transpose());
      }
    for (int axis = 0; axis < 3; ++axis) {
      if (hi[axis] < 1e-12) tags[f] = 1 + 2 * axis;
      if (lo[axis] > 1 - 1e-12) tags[f] = 2 + 2 * axis;
    }
  }
  return tags;
}

struct Selected {
  std::vector<char> faces;
  fem::PointFilter where;
};

Selected select_faces(const Selection& s, const std::vector<int>& face_tags,
                      const fem::FunctionSpace& space, const std::string& file) {
  Selected out;
  out.faces.assign(face_tags.size(), 0);
  long long count = 0;
  for (std::size_t f = 0; f < face_tags.size(); ++f) {
    const bool take = s.kind != Selection::Kind::tag || face_tags[f] == s.tag;
    out.faces[f] = take;
    count += take;
  }
  const bool pointwise = s.kind == Selection::Kind::box || s.kind == Selection::Kind::plane;
  if (pointwise) {
    out.where = [s](const Eigen::Vector3d& x) { return mapping::selects(s, {.x = x}); };
    // A region acts point-wise: it selects something only if a boundary DOF lies inside it.
    count = 0;
    fem::for_each_boundary_dof(space, out.faces, out.where, [&](int) { ++count; });
  }
  if (count == 0)
    throw InputError(
        s.where + ": selects no boundary face" +
            (s.kind == Selection::Kind::box ? std::string(" (no boundary node inside the box)")
             : s.kind == Selection::Kind::plane
                 ? std::string(" (no boundary node on the selected side of the plane)")
                 : std::string()) +
            (s.kind == Selection::Kind::tag
                 ? " (no boundary triangle has tag " + std::to_string(s.tag) + ")"
                 : ""),
        {.file = file});
  return out;
}

// ---- dense-surface pipelines (meshing.method curved | dense) --------------------------------

SurfaceMesh load_input_surface(const CaseSpec& spec) {
  SurfaceMesh input;
  if (spec.builtin_surface == "sphere")
    input = make_icosphere(spec.sphere_level, spec.radius);
  else if (spec.builtin_surface == "torus")
    input = make_torus(spec.torus_R, spec.torus_r, spec.torus_nu, spec.torus_nv);
  else if (spec.builtin_surface == "box")
    input = make_box(spec.box_lo, spec.box_hi, spec.box_divisions);
  else
    input = io::read_surface(spec.surface);
  const std::string where =
      spec.builtin_surface.empty() ? "/geometry/surface" : "/geometry/builtin_surface";
  const check::CheckReport report = check::check_surface(input, {});
  if (!report.acceptable)
    throw InputError(where + ": not a valid meshing input: " +
                         (report.defects.empty() ? std::string("empty surface")
                                                 : report.defects.front().message) +
                         (spec.surface.empty() ? std::string()
                                               : " (curvefem check " + spec.surface.string() +
                                                     " gives the full diagnosis)"),
                     {.file = spec.case_file.string()});
  return input;
}

std::vector<std::array<int, 2>> feature_edges(const CaseSpec& spec, const SurfaceMesh& input) {
  if (spec.features == "none") return {};
  if (spec.features != "file")
    return cv::detect_feature_edges(input, spec.features == "angle" ? spec.feature_angle : 60.0);
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

/// The mesh of a dense-surface pipeline and what maps between it and the input.
struct SurfacePipeline {
  SurfaceMesh input;
  std::optional<cv::CurvedMesh> curved;  // method curved
  BoundaryMap identity_map;              // method dense
  std::optional<mapping::BoundaryInverse> inverse;
  json report;
  bool valid = true;
  // The map with its boundary triangles on the solve's geometry (lower_geometry_for_solve), for
  // locating the solver's boundary points; φ itself is the curved mesh's.
  std::optional<BoundaryMap> solve_map;
  // Per tet of the curved mesh, from the validation (volume.vtu cell data): certificate,
  // scaled Jacobian, curved MIPS and the distortion of element_distortion.hpp.
  std::vector<Field> cell_quality;
  const BoundaryMap& map() const { return curved ? curved->map : identity_map; }
  // Exterior runs: the outer box (the mesh's bounding box) and the tolerance of a point on it.
  bool exterior = false;
  Eigen::Vector3d box_lo = Eigen::Vector3d::Zero(), box_hi = Eigen::Vector3d::Zero();
  double box_tol = 0;
  /// The side of the outer box x lies on, or -1 (always -1 without an exterior).
  int box_side(const Eigen::Vector3d& x) const {
    return exterior ? mapping::box_side_of(x, box_lo, box_hi, box_tol) : -1;
  }
  /// Where boundary data of the mesh point x are evaluated: φ⁻¹(x) on the input, or x itself on
  /// the outer box.
  Eigen::Vector3d data_point(const Eigen::Vector3d& x) const {
    return box_side(x) >= 0 ? x : inverse->at(x).position;
  }
};

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
void set_outer_box(SurfacePipeline& p, const LagrangeMesh& mesh, double padding) {
  p.exterior = true;
  std::tie(p.box_lo, p.box_hi) = vertex_bounding_box(mesh);
  p.box_tol = 1e-9 * (p.box_hi - p.box_lo).norm();
  p.report["exterior"] = {
      {"padding", padding},
      {"box", {{p.box_lo[0], p.box_lo[1], p.box_lo[2]}, {p.box_hi[0], p.box_hi[1], p.box_hi[2]}}},
      {"tets", mesh.num_cells()}};
}

/// Selection and value of a boundary condition at φ⁻¹(x) on the dense input. All boundary faces
/// are flagged; the point filter does the selecting, point-wise on the input.
Selected select_on_input(const BoundaryConditionSpec& bc, const SurfacePipeline& p,
                         const LagrangeMesh& mesh, const fem::FunctionSpace& space,
                         const std::string& file, bool weak_dirichlet) {
  const SurfaceMesh& input = p.input;
  const mapping::BoundaryInverse& inverse = *p.inverse;
  Selected out;
  out.faces.assign(space.boundary_faces.size(), 1);
  const Selection s = bc.select;
  if (s.kind != Selection::Kind::all && bc.type == "dirichlet" && mapping::uses_face_data(s)) {
    // The Dirichlet part is closed: a point on an input edge or vertex (where a feature chain
    // runs) is selected if any input face through it is, not by whichever face P returned.
    auto vf = std::make_shared<std::vector<std::vector<int>>>(input.num_vertices());
    for (int f = 0; f < input.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) (*vf)[std::size_t(input.F(f, k))].push_back(f);
    out.where = [s, &input, &inverse, vf](const Eigen::Vector3d& x) {
      const mapping::InputPoint p = inverse.at(x);
      if (mapping::selects(s, mapping::site_of(input, p))) return true;
      constexpr double tol = 1e-9;
      std::vector<int> others;
      for (int k = 0; k < 3; ++k) {
        const int a = input.F(p.face, k);
        if (p.bary[k] >= 1 - tol) others = (*vf)[std::size_t(a)];  // at that vertex
        if (std::abs(p.bary[k]) <= tol) {                          // on the edge opposite corner k
          const int b = input.F(p.face, (k + 1) % 3), c = input.F(p.face, (k + 2) % 3);
          for (int g : (*vf)[std::size_t(b)])
            for (int j = 0; j < 3; ++j)
              if (input.F(g, j) == c) others.push_back(g);
        }
      }
      for (int g : others) {
        if (g == p.face) continue;
        mapping::InputPoint q = p;
        q.face = g;
        if (mapping::selects(s, mapping::site_of(input, q))) return true;
      }
      return false;
    };
  } else if (s.kind != Selection::Kind::all) {
    out.where = [s, &input, &inverse](const Eigen::Vector3d& x) {
      return mapping::selects(s, mapping::site_of(input, inverse.at(x)));
    };
  }
  if (p.exterior) {
    // Exterior runs: points of the outer box are selected there (selects_point: only through
    // outer_box), the others on the input as above.
    out.where = [s, &p, on_input = out.where](const Eigen::Vector3d& x) {
      mapping::SelectionSite site;
      site.box_side = p.box_side(x);
      if (site.box_side < 0) return !on_input || on_input(x);
      site.x = x;
      return mapping::selects_point(s, site);
    };
  }
  // A Neumann selection, or a Dirichlet one imposed by Nitsche on faces it cuts, acts at the
  // face quadrature points the assembly uses; a nodal Dirichlet one at nodes.
  const bool at_points = bc.type == "neumann" || weak_dirichlet;
  long long count = 0;
  fem::for_each_boundary_dof(space, out.faces, out.where, [&](int) { ++count; });
  if (count == 0 && at_points)
    fem::for_each_face_point(
        mesh, space, out.faces,
        fem::default_quadrature_degree(space.degree, mesh.order, fem::QuadratureUse::mass),
        [&](int, int, const fem::FacePoint& p) { count += !out.where || out.where(p.x); });
  if (count == 0)
    throw InputError(s.where + ": selects no boundary " + (at_points ? "point" : "node") +
                         " of the mesh (the selected part of the input is smaller than the "
                         "mesh resolution)",
                     {.file = file});
  return out;
}

void build_surface_pipeline(const CaseSpec& spec, int threads, TerminalProgress& progress,
                            Timings& timings, LagrangeMesh& mesh, SurfacePipeline& p) {
  {
    ScopedTimer t(timings, "load_surface");
    progress.update("load surface", 0.0);
    p.input = load_input_surface(spec);
    for (const auto& bc : spec.boundary_conditions)
      if (!mapping::uses_outer_box(bc.select))  // may select the box only: checked on the mesh
        check_selection_on_input(bc.select, p.input, spec.case_file.string());
    progress.end_stage();
  }
  p.report["input_vertices"] = p.input.num_vertices();
  p.report["input_faces"] = p.input.num_faces();
  if (spec.method == "curved") {
    ScopedTimer t(timings, "meshing");
    cv::CurvedMeshOptions options;
    options.order = spec.order;
    options.eps_rel = spec.eps;
    options.thickness_rel = spec.thickness;
    options.thickness_per_edge = spec.thickness_per_edge;
    options.eps_samples = spec.eps_samples;
    options.feature_chains = spec.feature_chains;
    options.curved_coarsening = spec.curved_coarsening;
    options.threads = threads;
    options.deterministic = spec.deterministic;
    options.feature_edges = feature_edges(spec, p.input);
    options.exterior = spec.exterior;
    options.exterior_padding = spec.padding;
    cv::CurvedMeshStats stats;
    p.curved = cv::build_curved_mesh(p.input, options, stats, progress.callback());
    progress.end_stage();
    mesh = p.curved->mesh;
    json stages = json::object();
    for (const auto& [name, sec] : stats.stage_seconds) stages[name] = sec;
    p.report["feature_edges"] = stats.feature_edges;
    p.report["coarse_faces"] = stats.coarse_faces;
    p.report["slab_tets"] = stats.slab_tets;
    p.report["interior_tets"] = stats.interior_tets;
    p.report["faces_fully_curved"] = stats.faces_fully_curved;
    p.report["faces_blended"] = stats.faces_blended;
    p.report["faces_linear"] = stats.faces_linear;
    p.report["curve_refused"] = {{"certificate", stats.curve_refused_certificate},
                                 {"distance", stats.curve_refused_distance},
                                 {"deferred_outer", stats.curve_deferred_outer}};
    p.report["faces_recurved"] = stats.faces_recurved;
    p.report["faces_sheared"] = stats.faces_sheared;
    p.report["fiber_misses"] = stats.fiber_misses;
    p.report["linear_max_distance_rel"] = stats.linear_max_distance_rel;
    p.report["curved_coarsening"] = {
        {"curved_aware", stats.curved_coarsening},  {"attempts", stats.curved_attempts},
        {"strict_vertices", stats.strict_vertices}, {"widened", stats.curved_widened},
        {"repairs", stats.curved_repairs},          {"repair_splits", stats.repair_splits}};
    p.report["optimize"] = json::parse(optimize_json(stats.optimize).dump());
    p.report["stage_s"] = stages;
    if (spec.validate) {
      progress.update("validate mesh", 0.0);
      const cv::CurvedValidation v = cv::validate_curved_mesh(mesh, p.curved->map, p.input);
      p.report["validation"] = json::parse(curved_validation_json(v, spec.eps).dump());
      p.report["max_distance_rel"] = v.max_distance_rel;
      p.report["min_jacobian_certified"] = v.certified();
      p.valid = v.valid(spec.eps);
      p.cell_quality = curved_validation_cell_fields(v);
      progress.end_stage();
    }
    if (spec.exterior && spec.solve_on == "both") {
      // The whole box: the curved surface is an interface (its triangles are faces of a slab
      // tet and of an outer slab tet), the box the only boundary.
      p.report["outer_slab_tets"] = stats.outer_slab_tets;
      p.report["exterior_tets"] = stats.exterior_tets;
      set_outer_box(p, mesh, spec.padding);
    } else if (spec.exterior) {
      // The domain is the outside: the outer slab layer and the exterior (tags 3, 4; the whole
      // mesh was validated above). The map's triangles are faces of outer slab tets too.
      std::vector<int> old_to_new;
      mesh = extract_cells(mesh, {3, 4}, old_to_new);
      Eigen::VectorXi& to_volume = p.curved->map.boundary_node_to_volume;
      for (Eigen::Index i = 0; i < to_volume.size(); ++i)
        if (to_volume[i] >= 0) {
          to_volume[i] = old_to_new[std::size_t(to_volume[i])];
          if (to_volume[i] < 0)
            throw MeshingError("exterior: a node of the curved surface is in no outer tet");
        }
      p.report["outer_slab_tets"] = stats.outer_slab_tets;
      p.report["exterior_tets"] = stats.exterior_tets;
      set_outer_box(p, mesh, spec.padding);
    }
    p.inverse = mapping::BoundaryInverse::through_shell(p.curved->map, p.curved->shell, p.input);
  } else {
    ScopedTimer t(timings, "meshing");
    progress.update("tetrahedralize input", 0.0);
    meshing::tetfill::TetFillOptions options;
    options.threads = std::max(threads, 1);
    meshing::tetfill::TetFillResult fill;
    int inside_tets = 0;  // exterior, solve_on both: the first tets are the inside's
    if (!spec.exterior) {
      fill = meshing::tetfill::fill_interior(p.input.V, p.input.F, options);
    } else {
      // Outside the input, inside its bounding box padded as the curved mesher pads it: the
      // input enters reversed, as the box's cavity; its vertices stay first (φ = identity).
      const auto [lo, hi] = padded_bounding_box(p.input.V, spec.padding);
      const SurfaceMesh box = make_box(lo, hi, 4);
      const int nv = p.input.num_vertices();
      Eigen::MatrixXd V(nv + box.num_vertices(), 3);
      V << p.input.V, box.V;
      Eigen::MatrixXi F(p.input.num_faces() + box.num_faces(), 3);
      F.topRows(p.input.num_faces()) = p.input.F.rowwise().reverse();
      F.bottomRows(box.num_faces()) = box.F.array() + nv;
      fill = meshing::tetfill::fill_interior(V, F, options);
      if (spec.solve_on == "both") {
        // The inside too, sharing the input's vertices (both fills keep them first and keep the
        // input's triangles): its other vertices go after the outside's, its tets first.
        const meshing::tetfill::TetFillResult inside =
            meshing::tetfill::fill_interior(p.input.V, p.input.F, options);
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
    progress.end_stage();
    mesh = LagrangeMesh{};
    mesh.kind = CellKind::tetrahedron;
    mesh.order = 1;
    mesh.nodes = fill.V;
    mesh.cells = fill.T;
    if (spec.exterior) {
      mesh.cell_tags = Eigen::VectorXi::Constant(mesh.num_cells(), 4);
      mesh.cell_tags.head(inside_tets).setConstant(2);
      set_outer_box(p, mesh, spec.padding);
    }
    p.identity_map = mapping::make_identity_boundary_map(p.input);
    p.inverse = mapping::BoundaryInverse::identity(p.input);
    p.report["interior_vertices"] = fill.V.rows() - fill.boundary_vertices;
    p.report["tetfill_s"] = fill.seconds;
  }
}

// discretization.geometry "iso": a mesh of order k > p is solved on the degree-p interpolant of
// its maps (meshing/core/geometry_degree.hpp: a degree-p space on a degree-k map misses the
// linear functions, and P2 elasticity locked on curved slabs), once every tet of that interpolant
// is certified positive; otherwise, and with "mesh", on the mesh itself.
json lower_geometry_for_solve(const CaseSpec& spec, LagrangeMesh& mesh) {
  json r = {{"mode", spec.geometry}, {"mesh_order", mesh.order}, {"degree", mesh.order}};
  if (spec.geometry != "iso" || spec.degree >= mesh.order) return r;
  int kept = 0;
  mesh = lower_geometry_degree(
      mesh, spec.degree,
      [order = mesh.order](int, const Eigen::MatrixXd& X) {
        return meshing::curved::certify_tet_jacobian(order, X).verdict ==
               meshing::curved::JacobianVerdict::positive;
      },
      &kept);
  r["degree"] = spec.degree;
  r["tets"] = mesh.num_cells();
  r["tets_kept_at_mesh_order"] = kept;  // their degree-p interpolant was not certified positive
  if (kept > 0)
    log::info("run: " + std::to_string(kept) + " of " + std::to_string(mesh.num_cells()) +
              " tets keep their order-" + std::to_string(mesh.order) + " map (the degree-" +
              std::to_string(spec.degree) + " interpolant was not certified positive)");
  return r;
}

}  // namespace

RunOutcome run_case(const CaseSpec& spec, const RunSettings& settings, TerminalProgress& progress) {
  Timings timings;
  Stopwatch total;
  const std::string case_name = spec.case_file.string();

  LagrangeMesh mesh;
  fem::FunctionSpace space;
  std::vector<int> face_tags;
  SurfacePipeline pipeline;  // dense-surface methods only
  json solve_geometry;
  if (spec.dense_surface()) {
    build_surface_pipeline(spec, settings.threads, progress, timings, mesh, pipeline);
    ScopedTimer t(timings, "build_space");
    solve_geometry = lower_geometry_for_solve(spec, mesh);
    if (pipeline.curved && solve_geometry["degree"] != solve_geometry["mesh_order"]) {
      // Boundary data are read at the solver's points, on the lowered boundary: locate them on
      // the boundary triangles moved with it (same faces, same (u, v)).
      pipeline.solve_map = pipeline.curved->map;
      const Eigen::VectorXi& to_volume = pipeline.curved->map.boundary_node_to_volume;
      for (Eigen::Index i = 0; i < to_volume.size(); ++i)
        if (to_volume[i] >= 0)
          pipeline.solve_map->boundary.nodes.row(i) = mesh.nodes.row(to_volume[i]);
      pipeline.inverse = mapping::BoundaryInverse::through_shell(
          *pipeline.solve_map, pipeline.curved->shell, pipeline.input);
    }
    space = fem::build_function_space(mesh, spec.degree);
  } else {
    ScopedTimer t(timings, "load_mesh");
    progress.update("load mesh", 0.0);
    if (spec.builtin == "ball")
      mesh = io::make_ball_mesh(1.0, spec.builtin_size, spec.builtin_order);
    else if (spec.builtin == "cube")
      mesh = elevate_order(make_cube_tets(spec.builtin_divisions), spec.builtin_order,
                           [](const Eigen::Vector3d& x) { return x; });
    else
      mesh = load_mesh(spec.mesh);
    progress.update("build space", 0.5);
    solve_geometry = lower_geometry_for_solve(spec, mesh);
    space = fem::build_function_space(mesh, spec.degree);
    face_tags = spec.builtin == "cube" ? cube_face_tags(mesh, space)
                                       : boundary_face_tags(spec.mesh, mesh, space);
    progress.end_stage();
  }
  // Boundary data: on the mesh (given) or on the dense input through φ⁻¹ (curved, dense).
  auto select = [&](const BoundaryConditionSpec& bc) {
    return spec.dense_surface() ? select_on_input(bc, pipeline, mesh, space, case_name,
                                                  spec.partial_dirichlet == "nitsche")
                                : select_faces(bc.select, face_tags, space, case_name);
  };
  // Boundary values: on a dense input surface at data_point(x) (φ⁻¹(x) on the input), on a given
  // mesh at x; the normal of a Neumann value is the mesh's outward normal at the quadrature point
  // (the case file refuses nx, ny, nz in Dirichlet values).
  const SurfacePipeline* sp = &pipeline;
  const bool on_input = spec.dense_surface();
  const fem::PartialDirichlet partial_dirichlet = spec.partial_dirichlet == "nodal"
                                                      ? fem::PartialDirichlet::nodal
                                                      : fem::PartialDirichlet::nitsche;
  auto dirichlet_value = [&](const Expression& e) -> fem::ScalarField {
    if (!on_input) return [e](const Eigen::Vector3d& x) { return e(x); };
    return [e, sp](const Eigen::Vector3d& x) { return e(sp->data_point(x)); };
  };
  auto neumann_value = [&](const Expression& e) -> fem::BoundaryScalarField {
    if (!on_input)
      return [e](const Eigen::Vector3d& x, const Eigen::Vector3d& n) { return e(x, n); };
    return [e, sp](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
      return e(sp->data_point(x), n);
    };
  };
  log::info("mesh: ", mesh.num_cells(), " tetrahedra of order ", mesh.order, "; degree ",
            spec.degree, ": ", space.num_dofs, " nodes, ", space.boundary_faces.size(),
            " boundary faces");

  fem::LinearSolverOptions solver;
  solver.type = spec.solver;
  solver.rtol = spec.solver_rtol;
  solver.max_iterations = spec.solver_max_iterations;
  solver.use_near_nullspace = spec.solver_near_nullspace;
  const int c = spec.components();
  int null_space_dim = 0;  // pure Neumann / traction-only: the solution is determined up to it
  Eigen::VectorXd u;
  json physics_report;
  std::function<fem::ElasticMaterial(int)> cell_material;  // elasticity, solve_on both
  fem::LinearSolveInfo solve_info;
  progress.update("solve " + spec.physics, 0.0);
  if (spec.physics == "poisson") {
    fem::PoissonProblem problem;
    const Expression kappa = spec.kappa;
    problem.kappa = [kappa](const Eigen::Vector3d& x) { return kappa(x); };
    if (spec.solve_on == "both" && !spec.kappa_inside.empty()) {
      // Tags 1-2: inside the surface (slab layer, interior); 3-4: outside.
      const Expression inside = spec.kappa_inside;
      const Eigen::VectorXi* tags = &mesh.cell_tags;
      problem.cell_kappa = [kappa, inside, tags](int cell, const Eigen::Vector3d& x) {
        return (*tags)[cell] <= 2 ? inside(x) : kappa(x);
      };
    }
    if (!spec.rhs.empty()) {
      const Expression f = spec.rhs[0];
      problem.rhs = [f](const Eigen::Vector3d& x) { return f(x); };
    }
    problem.quadrature_degree = spec.quadrature;
    problem.partial_dirichlet = partial_dirichlet;
    for (const auto& bc : spec.boundary_conditions) {
      Selected sel = select(bc);
      if (bc.type == "dirichlet")
        problem.dirichlet.push_back({sel.faces, dirichlet_value(bc.value[0]), sel.where});
      else
        problem.neumann.push_back({sel.faces, neumann_value(bc.value[0]), sel.where});
    }
    const fem::PoissonSolution sol = fem::solve_poisson(mesh, space, problem, solver);
    u = sol.u;
    solve_info = sol.solve;
    for (const auto& [stage, s] : sol.timings.stages()) timings.add(stage, s);
    physics_report["free_dofs"] = sol.free_dofs;
    physics_report["nitsche_faces"] = sol.nitsche_faces;
    null_space_dim = sol.null_space_dim;
    if (null_space_dim > 0) {
      const fem::LoadCompatibility& cc = sol.compatibility;
      physics_report["null_space"] = {
          {"removed", "constants"},
          {"dimension", null_space_dim},
          {"solution", "mean zero (no Dirichlet condition: u is determined up to a constant)"},
          {"rhs_integral", sol.rhs_integral},
          {"flux_integral", sol.flux_integral},
          {"resultant", cc.resultant[0]},
          {"relative_imbalance", cc.relative},
          {"compatible", cc.compatible()},
          {"tolerance", fem::k_compatibility_tolerance}};
    }
  } else {
    fem::ElasticityProblem problem;
    problem.material = {spec.E, spec.nu};
    if (spec.solve_on == "both") {
      // Tags 1-2: inside the surface (slab layer, interior); 3-4: outside.
      const fem::ElasticMaterial inside{spec.E_inside.value_or(spec.E),
                                        spec.nu_inside.value_or(spec.nu)};
      const fem::ElasticMaterial outside = problem.material;
      const Eigen::VectorXi* tags = &mesh.cell_tags;
      problem.cell_material = [inside, outside, tags](int cell) {
        return (*tags)[cell] <= 2 ? inside : outside;
      };
    }
    cell_material = problem.cell_material;
    problem.quadrature_degree = spec.quadrature;
    problem.partial_dirichlet = partial_dirichlet;
    auto vector_field = [](const std::vector<Expression>& e) {
      return [e](const Eigen::Vector3d& x) { return Eigen::Vector3d(e[0](x), e[1](x), e[2](x)); };
    };
    auto at = [](const std::vector<Expression>& e, const Eigen::Vector3d& x,
                 const Eigen::Vector3d& n) {
      return Eigen::Vector3d(e[0](x, n), e[1](x, n), e[2](x, n));
    };
    auto dirichlet_field = [&](const std::vector<Expression>& e) -> fem::VectorField {
      if (!on_input) return vector_field(e);
      return [e, sp](const Eigen::Vector3d& x) {
        const Eigen::Vector3d y = sp->data_point(x);
        return Eigen::Vector3d(e[0](y), e[1](y), e[2](y));
      };
    };
    auto traction_field = [&](const std::vector<Expression>& e) -> fem::BoundaryVectorField {
      if (!on_input)
        return [e, at](const Eigen::Vector3d& x, const Eigen::Vector3d& n) { return at(e, x, n); };
      return [e, sp, at](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
        return at(e, sp->data_point(x), n);
      };
    };
    if (!spec.rhs.empty()) problem.body_force = vector_field(spec.rhs);
    for (const auto& bc : spec.boundary_conditions) {
      Selected sel = select(bc);
      if (bc.type == "dirichlet")
        problem.dirichlet.push_back(
            {sel.faces, bc.components, dirichlet_field(bc.value), sel.where});
      else
        problem.traction.push_back({sel.faces, traction_field(bc.value), sel.where});
    }
    fem::ElasticitySolution sol;
    if (spec.physics == "linear_elasticity") {
      sol = fem::solve_linear_elasticity(mesh, space, problem, solver);
    } else {
      fem::NewtonOptions newton;
      newton.load_steps = spec.load_steps;
      sol = fem::solve_neo_hookean(mesh, space, problem, solver, newton);
      json steps = json::array();
      for (const auto& s : sol.newton)
        steps.push_back({{"load_step", s.load_step},
                         {"iteration", s.iteration},
                         {"residual", s.residual},
                         {"step_length", s.step_length},
                         {"energy", s.energy}});
      physics_report["newton"] = steps;
    }
    u = sol.u;
    solve_info = sol.solve;
    for (const auto& [stage, s] : sol.timings.stages()) timings.add(stage, s);
    null_space_dim = sol.null_space_dim;
    auto vec = [](const Eigen::Vector3d& v) { return json::array({v[0], v[1], v[2]}); };
    if (null_space_dim > 0) {
      // Tractions only: no supports; the load's own balance is what counts.
      const fem::LoadCompatibility& cc = sol.compatibility;
      physics_report["null_space"] = {
          {"removed", "rigid motions"},
          {"dimension", null_space_dim},
          {"solution",
           "no mean translation or rotation (no Dirichlet condition: u is "
           "determined up to a rigid motion)"},
          {"total_force", vec(cc.resultant.head<3>())},
          {"total_moment", vec(cc.resultant.tail<3>())},
          {"moment_center", vec(cc.center)},
          {"relative_imbalance", cc.relative},
          {"compatible", cc.compatible()},
          {"tolerance", fem::k_compatibility_tolerance}};
    } else {
      // Equilibrium, recomputed from u: the supports' force against the applied load.
      ScopedTimer t(timings, "force_balance");
      const fem::ForceBalance fb =
          fem::force_balance(mesh, space, problem, u, spec.physics != "linear_elasticity");
      physics_report["force_balance"] = {{"applied", vec(fb.applied)},
                                         {"reaction", vec(fb.reaction)},
                                         {"supported_unknowns", fb.supported_unknowns},
                                         {"imbalance", fb.imbalance()}};
      if (fb.imbalance() > 1e-6)
        log::warn("force balance: applied + reaction is ", fb.imbalance(),
                  " of the load (the solve did not converge to equilibrium)");
    }
    physics_report["free_unknowns"] = sol.free_unknowns;
    if (spec.physics == "linear_elasticity") physics_report["nitsche_faces"] = sol.nitsche_faces;
    physics_report["E"] = spec.E;
    physics_report["nu"] = spec.nu;
  }
  progress.end_stage();

  json report;
  // The exact solution as compared: without Dirichlet data u_h is determined up to the null
  // space, so the errors are those of u_h − (u + r) with the mode r that takes out the null-space
  // part of u_h − u (its mean for Poisson); `exact` and `error` in the VTU files use u + r too.
  std::function<void(const Eigen::Vector3d&, double*)> exact_value;
  if (!spec.exact.empty()) {
    ScopedTimer t(timings, "errors");
    const auto exact = spec.exact;
    const fem::ExactValue value = [exact](const Eigen::Vector3d& x, double* v) {
      for (std::size_t i = 0; i < exact.size(); ++i) v[i] = exact[i](x);
    };
    const fem::ExactGradient gradient = [exact, grad = spec.exact_gradient](
                                            const Eigen::Vector3d& x, double* g) {
      for (std::size_t i = 0; i < exact.size(); ++i) {
        if (!grad.empty()) {
          for (int d = 0; d < 3; ++d) g[3 * i + d] = grad[3 * i + std::size_t(d)](x);
          continue;
        }
        const Eigen::Vector3d gi = exact[i].gradient(x);
        for (int d = 0; d < 3; ++d) g[3 * i + d] = gi[d];
      }
    };
    exact_value = value;
    fem::ErrorNorms e;
    if (null_space_dim > 0) {
      auto modes =
          std::make_shared<const fem::NullSpaceModes>(fem::null_space_modes(mesh, space, c));
      Eigen::VectorXd theta;
      e = fem::compute_errors_modulo_null_space(mesh, space, *modes, u, value, gradient, &theta);
      exact_value = [value, modes, theta](const Eigen::Vector3d& x, double* v) {
        double r[3];
        value(x, v);
        modes->evaluate(theta, x, r);
        for (int i = 0; i < modes->components; ++i) v[i] += r[i];
      };
      report["errors_modulo"] =
          c == 1 ? "constant: errors of u_h - (u + m), m = the mean of u_h - u (pure Neumann: u is "
                   "determined up to a constant)"
                 : "rigid motion: errors of u_h - (u + r), r = the rigid motion with the mean "
                   "translation and rotation of u_h - u (tractions only: u is determined up to a "
                   "rigid motion)";
      report["error_offset"] = std::vector<double>(theta.data(), theta.data() + theta.size());
    } else {
      e = fem::compute_errors(mesh, space, u, c, value, gradient);
    }
    report["l2_error"] = e.l2;
    report["h1_semi_error"] = e.h1_semi;
    report["h1_error"] = std::sqrt(e.l2 * e.l2 + e.h1_semi * e.h1_semi);
    report["l2_norm_exact"] = e.l2_exact;
    report["h1_semi_norm_exact"] = e.h1_semi_exact;
    report["exact_gradient"] =
        spec.exact_gradient.empty()
            ? "4th-order central differences of the exact expression, h = 1e-3"
            : "exact_gradient of the case (checked against those differences at 4 points)";
  }

  // Solution on the dense input: u_h at φ(v) for every input vertex v.
  MeshFields surface_fields;
  if (spec.dense_surface()) {
    ScopedTimer t(timings, "surface_transfer");
    const SurfaceMesh& input = pipeline.input;
    const mapping::SurfaceSamples samples = mapping::locate_input_vertices(mesh, pipeline.map());
    const Eigen::MatrixXd values = mapping::evaluate_on_surface(space, u, c, samples);
    const Eigen::MatrixXd images = mapping::sample_positions(mesh, samples);
    auto field = [](const std::string& name, const Eigen::MatrixXd& m) {
      Field f{name, int(m.cols()), {}};
      f.values.reserve(m.size());
      for (Eigen::Index r = 0; r < m.rows(); ++r)
        for (Eigen::Index i = 0; i < m.cols(); ++i) f.values.push_back(m(r, i));
      return f;
    };
    surface_fields.point_data.push_back(field(c == 1 ? "u" : "displacement", values));
    surface_fields.point_data.push_back(field("phi_offset", images - input.V));
    if (!spec.exact.empty()) {
      const mapping::SurfaceErrors e = mapping::surface_errors(input, values, exact_value);
      surface_fields.point_data.push_back(field("exact", e.exact));
      surface_fields.point_data.push_back(field("error", e.error));
      report["surface_l2_error"] = e.l2;
      report["surface_l2_norm_exact"] = e.l2_exact;
      report["surface_max_error"] = e.max;
    }
    report["surface_vertices"] = input.num_vertices();
    long long unmapped = 0;
    for (Eigen::Index v = 0; v < samples.cell.size(); ++v) unmapped += samples.cell[v] < 0;
    report["surface_unmapped_vertices"] = unmapped;
    for (std::size_t i = 0; i < spec.boundary_conditions.size(); ++i) {
      const auto& bc = spec.boundary_conditions[i];
      Field f{"bc" + std::to_string(i) + "_" + bc.type, 1, {}};
      for (int k = 0; k < input.num_faces(); ++k)
        f.values.push_back(mapping::face_coverage(bc.select, input, k));
      surface_fields.cell_data.push_back(f);
    }
  }

  // Output: nothing is written before this point; a failure while writing removes what was made.
  const bool existed = std::filesystem::exists(spec.output_dir);
  std::optional<StagedOutputDir> staged;
  try {
    staged.emplace(spec.output_dir);
    StagedOutputDir& out = *staged;
    {
      ScopedTimer t(timings, "output");
      progress.update("write output", 0.0);
      const int m = std::max(spec.degree, mesh.order);
      const fem::FunctionSpace out_space =
          m == spec.degree ? space : fem::build_function_space(mesh, m);
      const Eigen::MatrixXd values = fem::interpolate_field(space, u, c, out_space);
      MeshFields fields;
      Field uf{c == 1 ? "u" : "displacement", c, {}};
      uf.values.resize(values.size());
      for (int r = 0; r < values.rows(); ++r)
        for (int i = 0; i < c; ++i) uf.values[static_cast<std::size_t>(r) * c + i] = values(r, i);
      fields.point_data.push_back(uf);
      if (!spec.exact.empty()) {
        Field ef{"exact", c, {}}, err{"error", c, {}};
        for (int r = 0; r < out_space.num_dofs; ++r) {
          double ex[3];
          exact_value(out_space.dof_points.row(r).transpose(), ex);
          for (int i = 0; i < c; ++i) {
            ef.values.push_back(ex[i]);
            err.values.push_back(values(r, i) - ex[i]);
          }
        }
        fields.point_data.push_back(ef);
        fields.point_data.push_back(err);
      }
      if (spec.physics == "linear_elasticity") {
        const Eigen::VectorXd vm = fem::von_mises_at_dofs(
            mesh, out_space, {spec.E, spec.nu}, values.transpose().reshaped(), cell_material);
        fields.point_data.push_back(
            {"von_mises", 1, std::vector<double>(vm.data(), vm.data() + vm.size())});
      }
      for (const Field& f : sp->cell_quality)
        if (int(f.values.size()) == mesh.num_cells()) fields.cell_data.push_back(f);
      io::write_vtu(out.path("volume.vtu"), fem::lagrange_mesh_of_space(mesh, out_space), fields);
      write_text_file_atomic(out.path("resolved_case.json"), spec.resolved.dump(2) + "\n");
    }
    progress.end_stage();

    std::vector<io::PvdEntry> parts{{"volume.vtu", 0, 0.0, "volume"}};
    if (spec.dense_surface()) {
      LagrangeMesh surface;
      surface.kind = CellKind::triangle;
      surface.order = 1;
      surface.nodes = pipeline.input.V;
      surface.cells = pipeline.input.F;
      if (pipeline.input.has_tags()) surface.cell_tags = pipeline.input.tags;
      io::write_vtu(out.path("surface.vtu"), surface, surface_fields);
      parts.push_back({"surface.vtu", 1, 0.0, "surface"});
    }
    io::write_pvd(out.path("result.pvd"), parts);
    if (settings.paraview) {
      ParaviewScriptOptions script;
      script.dir = std::filesystem::absolute(spec.output_dir);
      script.field = c == 1 ? "u" : "displacement";
      script.components = c;
      script.surface = spec.dense_surface();
      script.exact = !spec.exact.empty();
      write_text_file_atomic(out.path("open_in_paraview.py"), paraview_state_script(script));
    }

    report["command"] = "run";
    report["case"] = spec.case_file.string();
    report["method"] = spec.method;
    if (spec.dense_surface()) {
      report["surface"] =
          spec.surface.empty() ? "builtin " + spec.builtin_surface : spec.surface.string();
      report["meshing"] = pipeline.report;
      report["mesh_valid"] = pipeline.valid;
    } else {
      report["mesh"] = spec.builtin.empty() ? spec.mesh.string() : "builtin " + spec.builtin;
    }
    report["tets"] = mesh.num_cells();
    report["order"] = mesh.order;
    report["degree"] = spec.degree;
    report["solve_geometry"] = solve_geometry;
    report["physics"] = spec.physics;
    report["dofs"] = static_cast<long long>(space.num_dofs) * c;
    report["nodes"] = space.num_dofs;
    report["physics_details"] = physics_report;
    report["solver"] = {{"method", solve_info.method},
                        {"iterations", solve_info.iterations},
                        {"relative_residual", solve_info.relative_residual},
                        {"setup_s", solve_info.setup_s},
                        {"solve_s", solve_info.solve_s},
                        {"near_nullspace", solve_info.near_nullspace},
                        {"null_space_dim", solve_info.null_space_dim}};
    timings.add("total", total.seconds());
    report["time_s"] = timings_json(timings);
    report["peak_rss_mb"] = peak_rss_mb();
    report["threads"] = settings.threads;
    write_text_file_atomic(out.path("report.json"), report.dump(2) + "\n");
    out.commit();
  } catch (...) {
    staged.reset();  // removes the staging folder
    std::error_code ec;
    if (!existed) std::filesystem::remove(spec.output_dir, ec);  // only if empty
    throw;
  }
  RunOutcome outcome;
  outcome.report = std::move(report);
  outcome.timings = std::move(timings);
  outcome.exit_code = pipeline.valid ? 0 : 3;
  return outcome;
}

namespace {

int run_command(const RunOptions& o) {
  auto progress = apply_global_options(o.global);
  const CaseSpec spec = read_case(o.case_file, o.output);
  const RunOutcome outcome =
      run_case(spec, {.threads = o.global.threads, .paraview = o.paraview}, *progress);
  const json& report = outcome.report;
  if (!o.global.quiet) {
    std::printf("curvefem run: %s (%s), degree %d on %d tets of order %d: %lld unknowns\n",
                spec.physics.c_str(), spec.method.c_str(), spec.degree, report["tets"].get<int>(),
                report["order"].get<int>(), report["dofs"].get<long long>());
    if (report.contains("l2_error"))
      std::printf("  L2 error %.3e   H1-semi error %.3e\n", report["l2_error"].get<double>(),
                  report["h1_semi_error"].get<double>());
    if (report.contains("surface_l2_error"))
      std::printf("  on the input surface (%d vertices): L2 error %.3e   max error %.3e\n",
                  report["surface_vertices"].get<int>(), report["surface_l2_error"].get<double>(),
                  report["surface_max_error"].get<double>());
    for (const auto& [stage, sec] : outcome.timings.stages())
      std::printf("  %-16s %8.3f s\n", stage.c_str(), sec);
    std::printf("  results in %s\n", spec.output_dir.c_str());
  }
  if (outcome.exit_code == 3)
    std::fprintf(stderr,
                 "curvefem run: the curved mesh failed its validation (see meshing.validation "
                 "in report.json)\n");
  return outcome.exit_code;
}

}  // namespace

void register_run(CLI::App& app) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* sub = app.add_subcommand("run", "solve the case described by a JSON case file");
  sub->add_option("case", options->case_file, "case file (schema: cases/README.md)")->required();
  sub->add_option("-o,--output", options->output, "output directory (overrides output.dir)");
  sub->add_flag("--paraview", options->paraview,
                "also write open_in_paraview.py (a ParaView Python state script)");
  add_global_options(*sub, options->global);
  add_command(sub, [options] { return run_command(*options); });
}

}  // namespace curvefem::cli
