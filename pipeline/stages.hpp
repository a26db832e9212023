// The stages of a case run (DESIGN.md §1), each a function with typed inputs and a typed result,
// callable alone (the CLI, `curvefem study`, the Python module and tests compose them):
//
//   load_surface      dense input surface (file or built-in), checked; selections checked on it
//   mesh_domain       curved (meshing/curved + independent validation) | dense (tetfill) | given
//   discretize        the solve geometry (degree-p interpolant in "iso" mode), function space,
//                     boundary face tags (given meshes), φ⁻¹ on the solve geometry
//   bind_boundary     boundary conditions bound to the mesh: face flags + point filters + values,
//                     evaluated on the dense input at φ⁻¹(x) (mapping/input_selection.hpp)
//   solve             Poisson | linear elasticity | Neo-Hookean (fem/problems)
//   compute_errors    L2/H1 against the case's exact solution (modulo the null space)
//   transfer_to_input the solution at φ(v) for every input vertex (mapping/surface_transfer.hpp)
//   write_outputs     volume.vtu, surface.vtu, result.pvd, resolved_case.json, report.json
//
// Stage results own their data; a later stage keeps references to earlier results (the Domain
// and Discretization must outlive what is bound to them). Progress goes to StageContext::progress
// (may be empty), stage times to StageContext::timings (may be null).
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fem/problems/boundary_conditions.hpp"
#include "fem/problems/elasticity.hpp"
#include "fem/problems/error_estimate.hpp"
#include "fem/problems/error_norms.hpp"
#include "fem/solvers/linear_solver.hpp"
#include "fem/space/function_space.hpp"
#include "mapping/boundary_inverse.hpp"
#include "meshing/check/check_surface.hpp"
#include "meshing/check/merge_short_edges.hpp"
#include "meshing/core/boundary_map.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/progress.hpp"
#include "meshing/core/shell_fibers.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::meshing::shell {
class InputSurfaceIndex;
}
#include "meshing/core/timer.hpp"
#include "pipeline/case_file.hpp"

namespace curvefem::pipeline {

struct StageContext {
  int threads = 0;             ///< 0 = all cores; also the curved mesher's workers
  ProgressFn progress;         ///< (stage, fraction); may be empty
  Timings* timings = nullptr;  ///< stage times are added here when set
  void update(std::string_view stage, double fraction) const {
    if (progress) progress(stage, fraction);
  }
};

// ---- load_surface ---------------------------------------------------------------------------

/// The dense input of a curved | dense case: read (or built), checked (InputError naming the
/// defect when `curvefem check` would reject it), and every boundary condition's selection checked
/// to select something on it. `warnings`, when given, receives `curvefem check`'s warnings as
/// report.json's `input_warnings` (a list; pipeline::defects_json), each also logged.
/// meshing.merge_short_edges: the input as read, and how the repaired surface (the one meshed,
/// Domain::input) relates to it (check/merge_short_edges.hpp).
struct InputRepair {
  SurfaceMesh original;
  std::vector<int> vertex_map;   ///< per original vertex: its vertex of the repaired surface
  std::vector<int> face_origin;  ///< per repaired face: its original face
  nlohmann::json report;         ///< report.json's meshing.input_repair
};

/// check::merge_short_edges of `input` at length_rel × its bbox, and the full check of the
/// result: InputError (`where`: the key or option, `file`) naming the first defect where the
/// repaired surface is not acceptable; the repair's summary logged.
struct MergedInput {
  check::MergeShortEdgesResult merge;
  check::CheckReport check;
  nlohmann::json summary;  ///< merge_summary_json
};
MergedInput merge_input(const SurfaceMesh& input, double length_rel, const std::string& where,
                        const std::string& file = {}, const ProgressFn& progress = {});

/// The distance bound on the input as read: max over its vertices v of |v - φ(vertex_map[v])|
/// (φ of the repaired surface; a merged-away vertex is measured from its replacement's image),
/// over the bbox's longest edge: {"max_distance_rel", "vertex", "within_eps"}.
nlohmann::json original_distance_json(const Eigen::MatrixXd& original_V,
                                      const std::vector<int>& vertex_map, const BoundaryMap& map,
                                      double eps_rel);

/// With meshing.merge_short_edges, the surface returned is the repaired one (checked again; its
/// warnings are those reported) and `repair`, when given, receives the original and the maps.
SurfaceMesh load_surface(const CaseSpec& spec, const StageContext& ctx = {},
                         nlohmann::json* warnings = nullptr, InputRepair* repair = nullptr);

/// The input feature edges of a case (geometry.features: auto | angle | file | none).
std::vector<std::array<int, 2>> case_feature_edges(const CaseSpec& spec, const SurfaceMesh& input);

// ---- mesh_domain ----------------------------------------------------------------------------

/// The outer box of an exterior run (the mesh's bounding box).
struct OuterBox {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
  double tol = 0;
  /// The side x lies on (0..5: x=lo, x=hi, y=lo, ...), or -1.
  int side(const Eigen::Vector3d& x) const;
};

/// The mesh the physics runs on and what ties its boundary to the dense input.
struct Domain {
  MeshingMethod method = MeshingMethod::given;
  LagrangeMesh mesh;  ///< as meshed (order k); volume.vtu's geometry
  // curved | dense:
  SurfaceMesh input;
  std::optional<BoundaryMap> curved_map;  ///< curved: φ
  /// curved: the fibers of the coarse shell the boundary was curved in (φ⁻¹ = P_T on them).
  std::shared_ptr<const ShellFibers> fibers;
  BoundaryMap identity_map;  ///< dense: φ = identity
  /// meshing.merge_short_edges: the input before the repair; surface_input.vtu shows the
  /// solution on its vertices (each merged-away vertex takes its repaired vertex's values).
  std::shared_ptr<const InputRepair> repair;
  std::optional<OuterBox> outer_box;  ///< exterior runs
  /// Per tet, from the independent validation (curved): certificate, scaled Jacobian, MIPS, ...
  std::vector<Field> cell_quality;
  bool valid = true;      ///< curved: the independent validation passed (or was not asked for)
  nlohmann::json report;  ///< report.json "meshing" (curved | dense)
  /// given, with geometry.data_surface: that surface's index; boundary values are read at the
  /// closest point of it.
  std::shared_ptr<const meshing::shell::InputSurfaceIndex> data_surface;
  const BoundaryMap& map() const { return curved_map ? *curved_map : identity_map; }
  bool on_input() const { return method != MeshingMethod::given; }
};

/// curved: build_curved_mesh + validate_curved_mesh, or the saved mesh of geometry.mesh_dir
/// (pipeline/mesh_dir.hpp); dense: tetfill of the input (φ = identity); given: the case's mesh
/// file or built-in mesh (`input` is ignored).
Domain mesh_domain(const CaseSpec& spec, SurfaceMesh input, const StageContext& ctx = {});

/// curved, meshing.eps a list (CaseSpec::eps_levels): one Domain per level, in that order, from
/// one shell and one coarsening (build_curved_mesh_levels), each validated at its own bound.
std::vector<Domain> mesh_domain_levels(const CaseSpec& spec, SurfaceMesh input,
                                       const StageContext& ctx = {});

// ---- discretize -----------------------------------------------------------------------------

struct Discretization {
  LagrangeMesh mesh;  ///< the solve geometry
  fem::FunctionSpace space;
  int components = 1;
  /// Given meshes: the physical tag of every boundary face of `space` (-1: none).
  std::vector<int> face_tags;
  /// curved | dense: φ⁻¹ on the solve geometry's boundary (the lowered one in "iso" mode).
  std::shared_ptr<const mapping::BoundaryInverse> inverse;
  std::shared_ptr<const BoundaryMap> solve_map;  ///< when the solve geometry differs from φ's
  nlohmann::json solve_geometry;                 ///< report.json "solve_geometry"
};

/// "iso": a mesh of order k > p is solved on the degree-p interpolant of its maps, where it is
/// certified positive (meshing/core/geometry_degree.hpp); "mesh": on the mesh's own maps.
Discretization discretize(const CaseSpec& spec, const Domain& domain, const StageContext& ctx = {});

// ---- bind_boundary --------------------------------------------------------------------------

struct BoundCondition {
  const BoundaryConditionSpec* spec = nullptr;
  std::vector<char> faces;  ///< per boundary face of the space
  fem::PointFilter where;   ///< empty: the whole flagged faces
};

/// The boundary conditions, bound to the mesh. On a dense input their selections are evaluated at
/// φ⁻¹(x), their values at data_point(x) (φ⁻¹(x); x on an exterior run's outer box or with
/// discretization.boundary_values_at "mesh"). InputError when a
/// selection selects no boundary node / point of the mesh.
struct BoundaryData {
  std::vector<BoundCondition> conditions;
  /// Where boundary data of the mesh point x are evaluated (identity on a given mesh).
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> data_point;
};

BoundaryData bind_boundary(const CaseSpec& spec,
                           const std::vector<BoundaryConditionSpec>& conditions,
                           const Domain& domain, const Discretization& disc);

// ---- solve ----------------------------------------------------------------------------------

struct Solution {
  Eigen::VectorXd u;  ///< #dofs × components, node-major
  int components = 1;
  int null_space_dim = 0;  ///< pure Neumann / traction-only: u is determined up to it
  fem::LinearSolveInfo solve;
  nlohmann::json physics;                                  ///< report.json "physics_details"
  std::function<fem::ElasticMaterial(int)> cell_material;  ///< elasticity, solve_on both
};

/// The case's physics with the bound conditions and body load `rhs` (empty, 1 or 3 expressions).
/// `cache` (linear physics, direct solver): the factorization is reused from an earlier solve of
/// an identical matrix (load cases with the same Dirichlet part), kept for the next otherwise.
Solution solve(const CaseSpec& spec, const Discretization& disc, const BoundaryData& data,
               const std::vector<Expression>& rhs, const StageContext& ctx = {},
               std::shared_ptr<fem::FactorizationCache> cache = nullptr);

// ---- compute_errors -------------------------------------------------------------------------

struct ErrorResult {
  /// The exact solution as compared (u + the null-space mode r when u_h is determined up to it).
  fem::ExactValue exact_value;
  nlohmann::json report;  ///< l2_error, h1_semi_error, ..., error_estimate
  /// The gradient-recovery indicator η_K per cell (fem/problems/error_estimate.hpp), computed
  /// with or without an exact solution; volume.vtu's cell field error_indicator.
  Eigen::VectorXd cell_estimate;
};

/// Errors of u_h against the load case's exact solution (an empty result without one).
ErrorResult compute_errors(const LoadCase& load, const Discretization& disc,
                           const Solution& solution, const StageContext& ctx = {});

// ---- transfer_to_input ----------------------------------------------------------------------

struct InputSolution {
  Eigen::MatrixXd values;  ///< #input V × components: u_h at v (output.surface_values)
  Eigen::MatrixXd images;  ///< #input V × 3: φ(v)
  MeshFields fields;       ///< surface.vtu: u, phi_offset, exact, error, bcN coverage
  nlohmann::json report;   ///< surface_* keys of report.json
};

/// u_h on every input vertex v (curved | dense domains only): at φ(v), continued to v to first
/// order with `extended` (output.surface_values); surface.vtu's fields, with the coverage of the
/// load case's selections.
InputSolution transfer_to_input(const LoadCase& load, const Domain& domain,
                                const Discretization& disc, const Solution& solution,
                                const ErrorResult& errors, const StageContext& ctx = {},
                                SurfaceValues values = SurfaceValues::extended);

/// Everything one load case gave.
struct LoadResult {
  LoadCase load;
  Solution solution;
  ErrorResult errors;
  std::optional<InputSolution> on_input;  ///< curved | dense
};

/// bind_boundary, solve, compute_errors and transfer_to_input for one load case.
LoadResult solve_load(const CaseSpec& spec, const LoadCase& load, const Domain& domain,
                      const Discretization& disc, const StageContext& ctx = {},
                      std::shared_ptr<fem::FactorizationCache> cache = nullptr);

// ---- write_outputs --------------------------------------------------------------------------

struct OutputOptions {
  bool paraview = false;             ///< also write open_in_paraview.py
  const Stopwatch* total = nullptr;  ///< when set, time_s gets "total" from it
};

/// The full report.json of a run (without time_s). One unnamed load case: its errors, solver and
/// physics at the top level, as always; named load cases: under "load_cases", one entry each.
nlohmann::json run_report(const CaseSpec& spec, const Domain& domain, const Discretization& disc,
                          const std::vector<LoadResult>& loads);

/// Writes volume.vtu and surface.vtu (every load case's fields; a named case's fields end in
/// "_<name>"), for named load cases also volume_<name>.vtu / surface_<name>.vtu as the time steps
/// of result.pvd, resolved_case.json, open_in_paraview.py (options.paraview) and `report` as
/// report.json (last), atomically into spec.output_dir: on a throw nothing new is left there.
/// `report` gets time_s (ctx.timings, with "total" from options.total) and peak_rss_mb.
void write_outputs(const CaseSpec& spec, const Domain& domain, const Discretization& disc,
                   const std::vector<LoadResult>& loads, const OutputOptions& options,
                   nlohmann::json& report, const StageContext& ctx = {});

}  // namespace curvefem::pipeline
