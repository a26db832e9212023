// Case files of `curvefem run`. The keys are the table of pipeline/case_schema.hpp (documented in
// cases/README.md's table, generated from it): every object's allowed keys, and the enums and
// numeric ranges of most keys, come from that table. Parsing is strict: an unknown key, a wrong
// type or a bad expression is an InputError naming the JSON path (e.g.
// "/boundary_conditions/1/select/box: expected [[x0,y0,z0],[x1,y1,z1]]"). The case is first
// resolved by the table (case_schema.hpp, resolve_case: unknown keys and keys whose rules fail are
// refused, defaults filled in); the parser then reads that resolved case, which is written as
// resolved_case.json. Relative paths resolve against the case file's folder.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "mapping/selection.hpp"
#include "pipeline/case_enums.hpp"
#include "pipeline/expression.hpp"

namespace curvefem::pipeline {

using Selection = mapping::Selection;

struct BoundaryConditionSpec {
  BoundaryType type = BoundaryType::dirichlet;
  Selection select;
  std::vector<Expression> value;  ///< 1 (scalar) or 3 (vector) expressions; robin: u_inf
  std::vector<Expression> h;      ///< robin: the coefficient h of −κ ∂u/∂n = h (u − u_inf)
  std::array<bool, 3> components{true, true, true};  ///< vector Dirichlet: which are imposed
};

/// One set of loads solved on a run's mesh and space: the body load, the boundary conditions and
/// optionally the exact solution (case key load_cases; without it the case's own top-level keys
/// are its one, unnamed, load case).
struct LoadCase {
  std::string name;             ///< "" for the top-level load case
  std::vector<Expression> rhs;  ///< empty, 1 or 3
  std::vector<BoundaryConditionSpec> boundary_conditions;
  std::vector<Expression> exact;           ///< empty, 1 or 3
  std::vector<Expression> exact_gradient;  ///< empty, or 3 per component of exact
};

struct CaseSpec {
  std::filesystem::path case_file;
  std::filesystem::path mesh;  ///< geometry.mesh, resolved (empty for a built-in shape)
  /// geometry.data_surface, resolved (given meshes): boundary values are read at the closest
  /// point of this surface, as for data painted on a dense surface the mesh approximates.
  std::filesystem::path data_surface;
  BuiltinVolume builtin = BuiltinVolume::none;  ///< geometry.builtin.shape
  double builtin_size = 0.3;                    ///< ball: target edge length (radius 1)
  int builtin_divisions = 4;                    ///< cube: n³ cubes of 6 tets on [0,1]³
  int builtin_order = 1;                        ///< geometric order k of the built-in mesh
  // Dense-surface pipelines (meshing.method curved | dense):
  std::filesystem::path surface;  ///< geometry.surface, resolved (empty for a built-in surface)
  BuiltinSurface builtin_surface = BuiltinSurface::none;  ///< geometry.builtin_surface.shape
  int sphere_level = 3;  ///< icosphere subdivisions (20·4^level faces)
  double radius = 1.0;   ///< sphere radius
  double torus_R = 1.0, torus_r = 0.4;
  int torus_nu = 48, torus_nv = 24;
  Eigen::Vector3d box_lo = Eigen::Vector3d::Zero(), box_hi = Eigen::Vector3d::Ones();
  int box_divisions = 4;
  /// geometry.mesh_dir, resolved: a curved mesh saved by `curvefem mesh` or a curved `run`
  /// (mesh.msh + boundary_map.json), reused without meshing; the input it was made from is read
  /// from the path saved with it and must still have the saved checksum.
  std::filesystem::path mesh_dir;
  FeatureMode features = FeatureMode::automatic;
  double feature_angle = 60.0;
  std::filesystem::path feature_file;
  MeshingMethod method = MeshingMethod::given;
  int order = 3;      ///< curved: geometric order k
  double eps = 1e-2;  ///< curved: distance bound, relative to the bbox edge
  /// curved, meshing.eps a list: the bounds, coarsest first (eps is then the finest). The run
  /// meshes them all from one coarsening and solves coarse to fine (run_case.hpp).
  std::vector<double> eps_levels;
  double thickness = 0.02;          ///< curved: shell half-thickness cap (relative)
  double thickness_per_edge = 1.0;  ///< curved: initial cap × each vertex's mean edge (0: off)
  /// curved | dense: the input's edges shorter than this × its bbox merged before meshing
  /// (check/merge_short_edges.hpp; 0: the input as it is).
  double merge_short_edges = 0;
  bool feature_chains = true;     ///< curved: coarsen along feature chains (snapped reference copy)
  bool curved_coarsening = true;  ///< curved: distance bound on the curved patch (order >= 2)
  std::string eps_field;  ///< curved: spatially varying ε, an expression of x, y, z ("" off)
  /// curved: ε per face tag of the input (key: tag value or name; relative bound); the bound at a
  /// vertex is the smallest of eps, eps_field and the bounds of the faces around it.
  std::map<std::string, double> eps_by_tag;
  int eps_samples = 0;   ///< curved: ε also at the degree-L lattice points of every input face
  bool validate = true;  ///< curved: independent validation of the mesh (report.json)
  bool deterministic = true;  ///< curved: single-threaded coarsening, bit-identical output
  /// curved | dense: solve outside the surface, out to its bounding box padded by `padding` ×
  /// the longest bbox edge (the inside is not part of the domain).
  bool exterior = false;
  double padding = 0.25;
  /// With exterior: "outside" (the domain is outside the surface) or "both" (the whole box; the
  /// surface is an interface, the outer box the only boundary).
  SolveOn solve_on = SolveOn::outside;
  bool dense_surface() const {
    return method == MeshingMethod::curved || method == MeshingMethod::dense;
  }
  Physics physics = Physics::poisson;
  Expression kappa;          ///< poisson
  Expression kappa_inside;   ///< poisson, solve_on both: κ inside the surface (empty: kappa)
  double E = 1.0, nu = 0.3;  ///< elasticity
  /// Elasticity, solve_on both: the inside's material (unset: E, nu).
  std::optional<double> E_inside, nu_inside;
  int load_steps = 1;  ///< neo_hookean
  int degree = 1;
  /// > 0: adaptive p (issue 22): from `degree` up to 4 on the same mesh until the relative
  /// gradient-recovery estimate η / ‖∇u_h‖ of every load case is at most this.
  double target_error = 0;
  int quadrature = -1;  ///< -1 = default
  /// Dirichlet faces a selection covers in part: "nitsche" (weakly; Poisson's default, linear
  /// elasticity on request) or "nodal" (the DOFs the selection covers are fixed; elasticity's
  /// default, Neo-Hookean's only mode).
  PartialDirichlet partial_dirichlet = PartialDirichlet::nitsche;
  /// "iso" (default): a mesh of order k > p is solved on the degree-p interpolant of its maps
  /// (meshing/core/geometry_degree.hpp), certified first; "mesh": on the mesh's own maps
  /// (super-parametric).
  SolveGeometry geometry = SolveGeometry::iso;
  /// curved | dense; "shifted" by default, "input" for neo_hookean (linear problems only).
  BoundaryValuesAt boundary_values_at = BoundaryValuesAt::shifted;
  std::vector<Expression> rhs;  ///< empty, 1 or 3
  std::vector<BoundaryConditionSpec> boundary_conditions;
  std::vector<Expression> exact;  ///< empty, 1 or 3
  /// Empty, or 3 per component of `exact` (∂/∂x, ∂/∂y, ∂/∂z of component 0, then 1, 2): the H1
  /// error uses them instead of finite differences of `exact`.
  std::vector<Expression> exact_gradient;
  /// load_cases: solved in turn on one mesh and one space (empty: the top-level rhs,
  /// boundary_conditions, exact and exact_gradient are the run's one load case).
  std::vector<LoadCase> load_cases;
  /// The load cases to solve: load_cases, or one unnamed case from the top-level keys.
  std::vector<LoadCase> loads() const {
    if (!load_cases.empty()) return load_cases;
    return {LoadCase{"", rhs, boundary_conditions, exact, exact_gradient}};
  }
  SolverType solver = SolverType::automatic;
  double solver_rtol = 1e-10;
  int solver_max_iterations = 5000;
  bool solver_near_nullspace = true;  ///< cg: rigid-body modes for GAMG (elasticity)
  Preconditioner solver_preconditioner = Preconditioner::gamg;  ///< cg
  ParallelPtap solver_parallel_ptap = ParallelPtap::automatic;  ///< GAMG over several ranks
  RankBalance solver_rank_balance = RankBalance::memory;        ///< several ranks
  std::filesystem::path output_dir;                             ///< resolved
  SurfaceValues surface_values = SurfaceValues::extended;       ///< output.surface_values
  nlohmann::json resolved;                                      ///< the case with defaults, as run
  int components() const { return physics == Physics::poisson ? 1 : 3; }
};

/// Reads and validates a case file; `output_override` replaces output.dir when non-empty.
CaseSpec read_case(const std::filesystem::path& path, const std::string& output_override = {});

/// Validates a case already parsed as JSON (e.g. one run of a study). `path` plays the role of the
/// case file: errors name it and relative paths resolve against its folder.
CaseSpec read_case_json(const nlohmann::json& j, const std::filesystem::path& path,
                        const std::string& output_override = {});

}  // namespace curvefem::pipeline
