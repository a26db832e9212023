// Stages bind_boundary and solve, and solve_load (stages.hpp).
#include <algorithm>
#include <cmath>
#include <memory>
#include <unordered_map>
#include <vector>

#include "fem/assembly/face_integration.hpp"
#include "fem/problems/constraints.hpp"
#include "fem/problems/elasticity.hpp"
#include "fem/problems/error_estimate.hpp"
#include "fem/problems/null_space.hpp"
#include "fem/problems/poisson.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "mapping/input_selection.hpp"
#include "mapping/selection.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/shell/shell_intersection.hpp"
#include "pipeline/stages.hpp"

namespace curvefem::pipeline {
namespace {
using json = nlohmann::json;

/// A selection of a given mesh's boundary faces (tags from the mesh file) or of its points.
BoundCondition bind_on_mesh(const BoundaryConditionSpec& bc, const Discretization& disc,
                            const std::string& file) {
  const Selection& s = bc.select;
  BoundCondition out;
  out.spec = &bc;
  out.faces.assign(disc.face_tags.size(), 0);
  long long count = 0;
  for (std::size_t f = 0; f < disc.face_tags.size(); ++f) {
    const bool take = s.kind != Selection::Kind::tag || disc.face_tags[f] == s.tag;
    out.faces[f] = take;
    count += take;
  }
  const bool pointwise = s.kind == Selection::Kind::box || s.kind == Selection::Kind::plane;
  if (pointwise) {
    out.where = [s](const Eigen::Vector3d& x) { return mapping::selects(s, {.x = x}); };
    // A region acts point-wise: it selects something only if a boundary DOF lies inside it.
    count = 0;
    fem::for_each_boundary_dof(disc.space, out.faces, out.where, [&](int) { ++count; });
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

/// A selection of the dense input, judged at φ⁻¹(x). All boundary faces are flagged; the point
/// filter does the selecting.
BoundCondition bind_on_input(const BoundaryConditionSpec& bc, const Domain& domain,
                             const Discretization& disc, const std::string& file,
                             bool weak_dirichlet) {
  const Selection& s = bc.select;
  BoundCondition out;
  out.spec = &bc;
  out.faces.assign(disc.space.boundary_faces.size(), 1);
  out.where = mapping::input_selection_filter(s, domain.input, disc.inverse,
                                              /*closed=*/bc.type == BoundaryType::dirichlet);
  if (domain.outer_box) {
    // Exterior runs: points of the outer box are selected there (selects_point: only through
    // outer_box), the others on the input as above.
    out.where = [s, box = *domain.outer_box, on_input = out.where](const Eigen::Vector3d& x) {
      mapping::SelectionSite site;
      site.box_side = box.side(x);
      if (site.box_side < 0) return !on_input || on_input(x);
      site.x = x;
      return mapping::selects_point(s, site);
    };
  }
  // A Neumann selection, or a Dirichlet one imposed by Nitsche on faces it cuts, acts at the
  // face quadrature points the assembly uses; a nodal Dirichlet one at nodes.
  const bool at_points =
      bc.type == BoundaryType::neumann || bc.type == BoundaryType::robin || weak_dirichlet;
  long long count = 0;
  fem::for_each_boundary_dof(disc.space, out.faces, out.where, [&](int) { ++count; });
  if (count == 0 && at_points)
    fem::for_each_face_point(
        disc.mesh, disc.space, out.faces,
        fem::default_quadrature_degree(disc.space.degree, disc.mesh.order,
                                       fem::QuadratureUse::mass),
        [&](int, int, const fem::FacePoint& p) { count += !out.where || out.where(p.x); });
  if (count == 0)
    throw InputError(s.where + ": selects no boundary " + (at_points ? "point" : "node") +
                         " of the mesh (the selected part of the input is smaller than the "
                         "mesh resolution)",
                     {.file = file});
  return out;
}

}  // namespace

BoundaryData bind_boundary(const CaseSpec& spec,
                           const std::vector<BoundaryConditionSpec>& conditions,
                           const Domain& domain, const Discretization& disc) {
  BoundaryData data;
  const std::string file = spec.case_file.string();
  for (const auto& bc : conditions)
    data.conditions.push_back(
        domain.on_input() ? bind_on_input(bc, domain, disc, file,
                                          spec.partial_dirichlet == PartialDirichlet::nitsche)
                          : bind_on_mesh(bc, disc, file));
  if (domain.on_input() && spec.boundary_values_at == BoundaryValuesAt::mesh) {
    // discretization.boundary_values_at "mesh": values are fields in space, read where the mesh
    // is (the selections above still judge φ⁻¹(x) on the input).
    data.data_point = [](const Eigen::Vector3d& x) { return x; };
  } else if (domain.on_input()) {
    std::optional<OuterBox> box = domain.outer_box;
    data.data_point = [box, inverse = disc.inverse](const Eigen::Vector3d& x) -> Eigen::Vector3d {
      if (box && box->side(x) >= 0) return x;
      return inverse->at(x).position;
    };
  } else if (domain.data_surface) {
    // geometry.data_surface: the closest point of that surface (a mesh approximating it, with
    // data painted on it).
    data.data_point = [index = domain.data_surface](const Eigen::Vector3d& x) {
      Eigen::Vector3d closest = x;
      index->closest_face(x, closest);
      return closest;
    };
  } else {
    data.data_point = [](const Eigen::Vector3d& x) { return x; };
  }
  return data;
}

// solver.type "auto": CHOLMOD up to this many unknowns, CG + GAMG above. The crossovers measured
// in benchmarks/results/solver_crossover.md (structured unit cubes, 2 threads, solve stage):
// Poisson P1-P3 and elasticity P1, direct faster at ~20k unknowns and CG from ~36k; elasticity P2
// even at 36-47k; elasticity P3 direct up to 89k, CG from 152k. P4 was not measured (P3's values).
namespace {
int auto_direct_max_unknowns(Physics physics, int degree) {
  if (physics == Physics::poisson) return 25000;
  if (degree <= 1) return 25000;
  if (degree == 2) return 40000;
  return 120000;
}

// The boundary DOF nearest to a point of the mesh's boundary (itself for a DOF point): a uniform
// grid of the boundary DOF points, searched in growing shells of cells.
class NearestBoundaryDof {
 public:
  explicit NearestBoundaryDof(const fem::FunctionSpace& space) : m_points(&space.dof_points) {
    for (int d = 0; d < space.num_dofs; ++d)
      if (space.on_boundary[std::size_t(d)]) m_ids.push_back(d);
    CF_VERIFY(!m_ids.empty(), "boundary shift: the space has no boundary DOF");
    m_lo = m_hi = point(m_ids[0]);
    for (int d : m_ids) {
      m_lo = m_lo.cwiseMin(point(d));
      m_hi = m_hi.cwiseMax(point(d));
    }
    const double extent = std::max((m_hi - m_lo).maxCoeff(), 1e-300);
    // About two points per cell on a surface of extent² area.
    m_cell = std::max(extent / std::sqrt(0.5 * double(m_ids.size())), extent * 1e-6);
    for (int d : m_ids) m_grid[key(index(point(d)))].push_back(d);
  }
  int operator()(const Eigen::Vector3d& x) const {
    const Eigen::Vector3i c = index(x);
    int best = -1;
    double best_d2 = HUGE_VAL;
    for (int r = 0;; ++r) {
      for (int i = -r; i <= r; ++i)
        for (int j = -r; j <= r; ++j)
          for (int k = -r; k <= r; ++k) {
            if (std::max({std::abs(i), std::abs(j), std::abs(k)}) != r) continue;
            const auto it = m_grid.find(key(c + Eigen::Vector3i(i, j, k)));
            if (it == m_grid.end()) continue;
            for (int d : it->second) {
              const double d2 = (point(d) - x).squaredNorm();
              if (d2 < best_d2) best_d2 = d2, best = d;
            }
          }
      // Every point of shell r + 1 and beyond is at least r · cell away.
      if (best >= 0 && double(r) * m_cell >= std::sqrt(best_d2)) return best;
      if (r > 4 * int(m_grid.size()) + 8) return best;  // a point far outside: the best seen
    }
  }

 private:
  Eigen::Vector3d point(int d) const { return m_points->row(d).transpose(); }
  Eigen::Vector3i index(const Eigen::Vector3d& x) const {
    return ((x - m_lo) / m_cell).array().floor().cast<int>();
  }
  static std::uint64_t key(const Eigen::Vector3i& c) {
    return (std::uint64_t(std::uint32_t(c[0]) & 0x1fffff) << 42) |
           (std::uint64_t(std::uint32_t(c[1]) & 0x1fffff) << 21) |
           (std::uint64_t(std::uint32_t(c[2]) & 0x1fffff));
  }
  const Eigen::MatrixXd* m_points;
  std::vector<int> m_ids;
  Eigen::Vector3d m_lo, m_hi;
  double m_cell = 1;
  std::unordered_map<std::uint64_t, std::vector<int>> m_grid;
};

// discretization.boundary_values_at "shifted": Dirichlet values g(y), y = φ⁻¹(x) read on the
// input, continued from y to the mesh point x with the recovered gradient G of the first solution,
// u(x) ≈ g(y) + G(x)·(x − y) (the Taylor condition of the shifted boundary method, Main &
// Scovazzi 2018, imposed by one re-solve: the stiffness does not change). One pass, not a fixed
// point: iterated, G feeds on its own corrections and diverged on homer (k = 3, ε = 1%, P3: the
// largest change per pass 0.020, 0.033, 0.21, 1.3, 8.3; H1-semi error 0.013 after one pass, 5.2
// after five), while one pass is a bounded correction of a bounded first solution.
constexpr int k_shift_passes = 1;
}  // namespace

Solution solve(const CaseSpec& spec, const Discretization& disc, const BoundaryData& data,
               const std::vector<Expression>& rhs, const StageContext& ctx,
               std::shared_ptr<fem::FactorizationCache> cache) {
  const LagrangeMesh& mesh = disc.mesh;
  const fem::FunctionSpace& space = disc.space;
  ctx.update("solve " + to_string(spec.physics), 0.0);
  fem::LinearSolverOptions solver;
  solver.type = fem::solver_type_from(to_string(spec.solver));
  solver.rtol = spec.solver_rtol;
  solver.max_iterations = spec.solver_max_iterations;
  solver.use_near_nullspace = spec.solver_near_nullspace;
  solver.preconditioner = fem::preconditioner_from(to_string(spec.solver_preconditioner));
  solver.parallel_ptap =
      spec.solver_parallel_ptap == ParallelPtap::scalable    ? fem::ParallelPtap::scalable
      : spec.solver_parallel_ptap == ParallelPtap::allatonce ? fem::ParallelPtap::allatonce
                                                             : fem::ParallelPtap::automatic;
  solver.rank_balance = spec.solver_rank_balance == RankBalance::rows ? fem::RankBalance::rows
                                                                      : fem::RankBalance::memory;
  solver.auto_direct_max_dofs = auto_direct_max_unknowns(spec.physics, disc.space.degree);
  if (spec.physics != Physics::neo_hookean) solver.factorization_cache = std::move(cache);
  const fem::PartialDirichlet partial_dirichlet = spec.partial_dirichlet == PartialDirichlet::nodal
                                                      ? fem::PartialDirichlet::nodal
                                                      : fem::PartialDirichlet::nitsche;
  // Boundary values are read at data_point(x): φ⁻¹(x) on a dense input, x on a given mesh. The
  // normal of a Neumann value is the mesh's outward normal at the quadrature point.
  // Only a curved mesh's boundary lies off the input (dense: φ = identity, nothing to shift).
  const bool shift = spec.boundary_values_at == BoundaryValuesAt::shifted &&
                     spec.method == MeshingMethod::curved && spec.physics != Physics::neo_hookean;
  std::shared_ptr<const NearestBoundaryDof> nearest;
  if (shift) {
    nearest = std::make_shared<const NearestBoundaryDof>(space);
    // The passes re-solve with the same stiffness: one factorization.
    if (!solver.factorization_cache)
      solver.factorization_cache = std::make_shared<fem::FactorizationCache>();
  }
  json shift_passes = json::array();
  // Values of the previous solution's continuation at the mesh point: G(x)·(x − y), G the
  // recovered gradient (3 columns per component) at x's nearest boundary DOF.
  auto shift_of = [&nearest](const std::shared_ptr<const Eigen::MatrixXd>& G, int component,
                             const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
    const int d = (*nearest)(x);
    return G->row(d).segment<3>(3 * component).dot((x - y).transpose());
  };
  const auto point = data.data_point;
  Solution out;
  out.components = spec.components();
  auto add_stages = [&](const Timings& t) {
    if (ctx.timings)
      for (const auto& [stage, s] : t.stages()) ctx.timings->add(stage, s);
  };
  if (spec.physics == Physics::poisson) {
    fem::PoissonProblem problem;
    const Expression kappa = spec.kappa;
    if (const auto value = kappa.constant())
      problem.kappa_value = *value;  // lets straight cells use the reference tensors
    else
      problem.kappa = [kappa](const Eigen::Vector3d& x) { return kappa(x); };
    if (spec.solve_on == SolveOn::both && !spec.kappa_inside.empty()) {
      // Tags 1-2: inside the surface (slab layer, interior); 3-4: outside.
      const Expression inside = spec.kappa_inside;
      const Eigen::VectorXi* tags = &mesh.cell_tags;
      problem.cell_kappa = [kappa, inside, tags](int cell, const Eigen::Vector3d& x) {
        return (*tags)[cell] <= 2 ? inside(x) : kappa(x);
      };
    }
    if (!rhs.empty()) {
      const Expression f = rhs[0];
      problem.rhs = [f](const Eigen::Vector3d& x) { return f(x); };
      problem.rhs_batch = [f](const Eigen::MatrixXd& x, Eigen::VectorXd& values) {
        f.values_and_gradients(static_cast<int>(x.rows()), x.col(0).data(), x.col(1).data(),
                               x.col(2).data(), values.data(), nullptr, nullptr, nullptr);
      };
    }
    problem.quadrature_degree = spec.quadrature;
    problem.partial_dirichlet = partial_dirichlet;
    for (const BoundCondition& bc : data.conditions) {
      const Expression e = bc.spec->value[0];
      if (bc.spec->type == BoundaryType::dirichlet)
        problem.dirichlet.push_back(
            {bc.faces, [e, point](const Eigen::Vector3d& x) { return e(point(x)); }, bc.where});
      else if (bc.spec->type == BoundaryType::robin)
        problem.robin.push_back(
            {bc.faces,
             [h = bc.spec->h[0], point](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
               return h(point(x), n);
             },
             [e, point](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
               return e(point(x), n);
             },
             bc.where});
      else
        problem.neumann.push_back({bc.faces,
                                   [e, point](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
                                     return e(point(x), n);
                                   },
                                   bc.where});
    }
    fem::PoissonSolution sol = fem::solve_poisson(mesh, space, problem, solver);
    add_stages(sol.timings);
    for (int pass = 0; shift && !problem.dirichlet.empty() && pass < k_shift_passes; ++pass) {
      const auto G =
          std::make_shared<const Eigen::MatrixXd>(fem::recover_gradient(mesh, space, sol.u, 1));
      std::size_t i = 0;
      for (const BoundCondition& bc : data.conditions)
        if (bc.spec->type == BoundaryType::dirichlet)
          problem.dirichlet[i++].value = [e = bc.spec->value[0], point, G,
                                          shift_of](const Eigen::Vector3d& x) {
            const Eigen::Vector3d y = point(x);
            return e(y) + shift_of(G, 0, x, y);
          };
      const Eigen::VectorXd before = sol.u;
      sol = fem::solve_poisson(mesh, space, problem, solver);
      add_stages(sol.timings);
      shift_passes.push_back({{"max_change", (sol.u - before).cwiseAbs().maxCoeff()}});
    }
    out.u = sol.u;
    out.solve = sol.solve;
    out.physics["load_functional"] = {
        {"value", sol.load_functional},
        {"volume", sol.load_functional_volume},
        {"definition",
         "l(u_h) = integral of f u_h + of g u_h over the Neumann faces + of h u_inf u_h over the "
         "Robin faces, on this mesh (the load vector times u_h); volume: its part integral of f "
         "u_h (faces a selection cuts are integrated with an indicator at the quadrature points, "
         "first-order accurate at the cut: the volume part has no such term)"}};
    out.physics["free_dofs"] = sol.free_dofs;
    out.physics["nitsche_faces"] = sol.nitsche_faces;
    out.null_space_dim = sol.null_space_dim;
    if (out.null_space_dim > 0) {
      const fem::LoadCompatibility& cc = sol.compatibility;
      out.physics["null_space"] = {
          {"removed", "constants"},
          {"dimension", out.null_space_dim},
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
    if (spec.solve_on == SolveOn::both) {
      // Tags 1-2: inside the surface (slab layer, interior); 3-4: outside.
      const fem::ElasticMaterial inside{spec.E_inside.value_or(spec.E),
                                        spec.nu_inside.value_or(spec.nu)};
      const fem::ElasticMaterial outside = problem.material;
      const Eigen::VectorXi* tags = &mesh.cell_tags;
      problem.cell_material = [inside, outside, tags](int cell) {
        return (*tags)[cell] <= 2 ? inside : outside;
      };
    }
    out.cell_material = problem.cell_material;
    problem.quadrature_degree = spec.quadrature;
    problem.partial_dirichlet = partial_dirichlet;
    if (!rhs.empty())
      problem.body_force = [e = rhs](const Eigen::Vector3d& x) {
        return Eigen::Vector3d(e[0](x), e[1](x), e[2](x));
      };
    for (const BoundCondition& bc : data.conditions) {
      const std::vector<Expression> e = bc.spec->value;
      if (bc.spec->type == BoundaryType::dirichlet)
        problem.dirichlet.push_back({bc.faces, bc.spec->components,
                                     [e, point](const Eigen::Vector3d& x) {
                                       const Eigen::Vector3d y = point(x);
                                       return Eigen::Vector3d(e[0](y), e[1](y), e[2](y));
                                     },
                                     bc.where});
      else
        problem.traction.push_back({bc.faces,
                                    [e, point](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
                                      const Eigen::Vector3d y = point(x);
                                      return Eigen::Vector3d(e[0](y, n), e[1](y, n), e[2](y, n));
                                    },
                                    bc.where});
    }
    fem::ElasticitySolution sol;
    if (spec.physics == Physics::linear_elasticity) {
      sol = fem::solve_linear_elasticity(mesh, space, problem, solver);
      for (int pass = 0; shift && !problem.dirichlet.empty() && pass < k_shift_passes; ++pass) {
        add_stages(sol.timings);
        const auto G =
            std::make_shared<const Eigen::MatrixXd>(fem::recover_gradient(mesh, space, sol.u, 3));
        std::size_t i = 0;
        for (const BoundCondition& bc : data.conditions)
          if (bc.spec->type == BoundaryType::dirichlet)
            problem.dirichlet[i++].value = [e = bc.spec->value, point, G,
                                            shift_of](const Eigen::Vector3d& x) {
              const Eigen::Vector3d y = point(x);
              return Eigen::Vector3d(e[0](y) + shift_of(G, 0, x, y), e[1](y) + shift_of(G, 1, x, y),
                                     e[2](y) + shift_of(G, 2, x, y));
            };
        const Eigen::VectorXd before = sol.u;
        sol = fem::solve_linear_elasticity(mesh, space, problem, solver);
        shift_passes.push_back({{"max_change", (sol.u - before).cwiseAbs().maxCoeff()}});
      }
    } else {
      fem::NewtonOptions newton;
      newton.load_steps = spec.load_steps;
      sol = fem::solve_neo_hookean(mesh, space, problem, solver, newton);
      json steps = json::array();
      for (const auto& s : sol.newton)
        steps.push_back({{"load_step", s.load_step},
                         {"load", s.load},
                         {"iteration", s.iteration},
                         {"residual", s.residual},
                         {"step_length", s.step_length},
                         {"energy", s.energy}});
      out.physics["newton"] = steps;
      out.physics["load_cuts"] = sol.load_cuts;
    }
    out.u = sol.u;
    out.solve = sol.solve;
    add_stages(sol.timings);
    out.null_space_dim = sol.null_space_dim;
    out.physics["load_functional"] = {
        {"value", sol.load_functional},
        {"volume", sol.load_functional_volume},
        {"definition",
         spec.physics == Physics::linear_elasticity
             ? "l(u_h) = integral of b.u_h + of t.u_h over the traction faces, on this mesh (the "
               "external load vector times u_h; the compliance when the supports do not move); "
               "volume: its part integral of b.u_h"
             : "l(u_h) = integral of b.u_h + of t.u_h over the traction faces at the last load "
               "step, on this mesh (the external load vector times u_h); volume: its part "
               "integral of b.u_h"}};
    auto vec = [](const Eigen::Vector3d& v) { return json::array({v[0], v[1], v[2]}); };
    if (out.null_space_dim > 0) {
      // Tractions only: no supports; the load's own balance is what counts.
      const fem::LoadCompatibility& cc = sol.compatibility;
      out.physics["null_space"] = {{"removed", "rigid motions"},
                                   {"dimension", out.null_space_dim},
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
      std::optional<ScopedTimer> t;
      if (ctx.timings) t.emplace(*ctx.timings, "force_balance");
      const fem::ForceBalance fb = fem::force_balance(mesh, space, problem, out.u,
                                                      spec.physics != Physics::linear_elasticity);
      out.physics["force_balance"] = {{"applied", vec(fb.applied)},
                                      {"reaction", vec(fb.reaction)},
                                      {"supported_unknowns", fb.supported_unknowns},
                                      {"imbalance", fb.imbalance()}};
      if (fb.imbalance() > 1e-6)
        log::warn("force balance: applied + reaction is ", fb.imbalance(),
                  " of the load (the solve did not converge to equilibrium)");
    }
    out.physics["free_unknowns"] = sol.free_unknowns;
    if (spec.physics == Physics::linear_elasticity)
      out.physics["nitsche_faces"] = sol.nitsche_faces;
    out.physics["E"] = spec.E;
    out.physics["nu"] = spec.nu;
  }
  if (shift)
    out.physics["boundary_shift"] = {
        {"method",
         "Dirichlet values g(y), y = phi^-1(x) on the input, continued to the mesh point x with "
         "the recovered gradient of the previous solution: g(y) + G(x).(x - y); one re-solve per "
         "pass (same stiffness)"},
        {"passes", shift_passes}};
  ctx.update("solve " + to_string(spec.physics), 1.0);
  return out;
}

LoadResult solve_load(const CaseSpec& spec, const LoadCase& load, const Domain& domain,
                      const Discretization& disc, const StageContext& ctx,
                      std::shared_ptr<fem::FactorizationCache> cache) {
  LoadResult r;
  r.load = load;
  const BoundaryData data = bind_boundary(spec, r.load.boundary_conditions, domain, disc);
  r.solution = solve(spec, disc, data, r.load.rhs, ctx, std::move(cache));
  r.errors = compute_errors(r.load, disc, r.solution, ctx);
  if (domain.on_input())
    r.on_input =
        transfer_to_input(r.load, domain, disc, r.solution, r.errors, ctx, spec.surface_values);
  return r;
}

}  // namespace curvefem::pipeline
