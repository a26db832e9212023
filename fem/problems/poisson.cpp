#include "fem/problems/poisson.hpp"

#include <utility>

#include "fem/assembly/element_geometry.hpp"
#include "fem/assembly/face_integration.hpp"
#include "fem/assembly/parallel_assembly.hpp"
#include "fem/problems/constraints.hpp"
#include "fem/problems/kept_operator.hpp"
#include "fem/problems/nitsche.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "fem/solvers/distributed.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"

namespace curvefem::fem {

namespace {

/// κ at point x of a cell: the per-cell field, else the field, else the constant.
double kappa_at(const PoissonProblem& problem, int cell, const Eigen::Vector3d& x) {
  return problem.cell_kappa ? problem.cell_kappa(cell, x)
         : problem.kappa    ? problem.kappa(x)
                            : problem.kappa_value;
}

int stiffness_quadrature(const LagrangeMesh& mesh, const FunctionSpace& space,
                         const PoissonProblem& problem) {
  return problem.quadrature_degree >= 0 ? problem.quadrature_degree
                                        : tetrahedron_degree_at_same_cost(default_quadrature_degree(
                                              space.degree, mesh.order, QuadratureUse::stiffness));
}

/// The cell part of K (before the Robin terms), kept in the solver's FactorizationCache for the
/// next solve on the same mesh, space, quadrature and κ (the shifted values' re-solves, the load
/// cases of a run). The κ functions cannot be compared: a cache is shared only by solves of one
/// problem's coefficients, on a mesh not changed meanwhile (as for elasticity's KeptStiffness).
struct KeptPoissonStiffness : KeptOperator {
  KeptDiscretization on;
  double kappa_value;
  bool kappa_field, cell_kappa;
  std::shared_ptr<const SparsePattern> pattern;
  SparseMatrix K;
  KeptPoissonStiffness(const LagrangeMesh& m, const FunctionSpace& s, const PoissonProblem& p,
                       int q)
      : on(m, s, q),
        kappa_value(p.kappa_value),
        kappa_field(static_cast<bool>(p.kappa)),
        cell_kappa(static_cast<bool>(p.cell_kappa)) {}
  bool matches(const LagrangeMesh& m, const FunctionSpace& s, const PoissonProblem& p,
               int q) const {
    return on.same(m, s, q) && kappa_value == p.kappa_value &&
           kappa_field == static_cast<bool>(p.kappa) &&
           cell_kappa == static_cast<bool>(p.cell_kappa);
  }
};

/// Robin: ∫ h φ_a φ_b into K (the parts' rows) and ∫ h u∞ φ_a into F (with the load) at the
/// same face points (a face's DOFs all belong to its cell, so every entry is in the pattern).
void add_robin(const LagrangeMesh& mesh, const FunctionSpace& space, const PoissonProblem& problem,
               const AssemblyParts& parts, AssembledSystem& system) {
  const int n = static_cast<int>(space.cell_dofs.cols());
  const int face_degree = default_quadrature_degree(space.degree, mesh.order, QuadratureUse::mass);
  for (const auto& bc : problem.robin) {
    const FacePoints points = face_points(mesh, space, bc.faces, face_degree);
    std::vector<double> h(points.size(), 0.0), u_inf(points.size(), 0.0);
    const std::vector<char> used =
        evaluate_at_face_points(points, bc.where, [&](int k, const Eigen::Vector3d& x) {
          const Eigen::Vector3d normal = points.normal.row(k).transpose();
          h[std::size_t(k)] = bc.h(x, normal);
          u_inf[std::size_t(k)] = bc.u_inf(x, normal);
        });
    for (int k = 0; k < points.size(); ++k) {
      if (!used[k]) continue;
      if (!(h[k] > 0))
        throw InputError("Robin condition: the coefficient h is " + std::to_string(h[k]) + " at (" +
                         std::to_string(points.x(k, 0)) + ", " + std::to_string(points.x(k, 1)) +
                         ", " + std::to_string(points.x(k, 2)) + "); it must be positive");
      const double w = h[k] * points.ds_w[k];
      system.robin_area += points.ds_w[k];
      const double* phi = points.basis.row(points.basis_row[k]).data();
      const int cell = points.cell[k];
      for (int a = 0; a < n; ++a) {
        const int da = space.cell_dofs(cell, a);
        if (parts.load) system.F[da] += w * u_inf[k] * phi[a];
        for (int b = 0; b < n; ++b) {
          const int db = space.cell_dofs(cell, b);
          if (parts.keeps(db)) system.K.coeffRef(da, db) += w * phi[a] * phi[b];
        }
      }
    }
  }
}

/// assemble_poisson, taking the cell part of K from `kept_in` (then only F is assembled over the
/// cells) or leaving a copy of it, with its pattern, in `kept_out`; `parts` says what to compute
/// (without kept_in/kept_out unless whole).
AssembledSystem assemble_poisson_kept(const LagrangeMesh& mesh, const FunctionSpace& space,
                                      const PoissonProblem& problem,
                                      const KeptPoissonStiffness* kept_in,
                                      KeptPoissonStiffness* kept_out,
                                      const AssemblyParts& parts = {}) {
  const int p = space.degree;
  const int degree = stiffness_quadrature(mesh, space, problem);
  const QuadratureRule& rule = tetrahedron_quadrature(degree);
  const GeometryEvaluator geometry(mesh, rule.points, rule.weights);
  const ReferenceTabulation basis = tabulate(CellKind::tetrahedron, p, rule.points);
  const int n = static_cast<int>(space.cell_dofs.cols());
  CF_VERIFY(parts.matrix || parts.load, "assemble_poisson: nothing to assemble");
  CF_VERIFY((parts.matrix && parts.load && !parts.rows) || (!kept_in && !kept_out),
            "assemble_poisson: a kept stiffness with a partial assembly");
  const bool with_matrix = kept_in == nullptr && parts.matrix;
  const bool with_load = parts.load;
  const std::shared_ptr<const SparsePattern> pattern =
      kept_in ? kept_in->pattern
      : with_matrix
          ? std::make_shared<const SparsePattern>(space.cell_dofs, space.num_dofs, 1, parts.rows)
          : nullptr;
  AssembledSystem system;
  if (pattern) system.K = kept_in ? kept_in->K : pattern->zero_matrix();
  if (with_load) system.F = Eigen::VectorXd::Zero(space.num_dofs);

  const int nq = geometry.num_points();
  // Straight cells and a constant κ: K_e = κ det J Σ_ij C_ij S_ij with C = J⁻¹J⁻ᵀ and the reference
  // tensors S_ij = Σ_q w_q ∇̂φ_i ∇̂φ_jᵀ (symmetrized pairs: six n×n matrices, one column each of
  // T), the same integral as the point loop below for an affine map, at 6n² operations per cell.
  const bool tensor = mesh.order == 1 && !problem.kappa && !problem.cell_kappa;
  Eigen::MatrixXd T;
  if (tensor) {
    static constexpr int pairs[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    T.setZero(n * n, 6);
    Eigen::MatrixXd S(n, n);
    for (int q = 0; q < nq; ++q)
      for (int k = 0; k < 6; ++k) {
        const auto& B = basis.gradients[q];
        const int i = pairs[k][0], j = pairs[k][1];
        S.noalias() = rule.weights[q] * B.col(i) * B.col(j).transpose();
        if (i != j) S += S.transpose().eval();
        T.col(k) += S.reshaped();
      }
  }
  const ElementKernel kernel = [&](int cell, Eigen::MatrixXd& Ke, Eigen::VectorXd& Fe) {
    // Per-thread scratch: no allocation per cell after the first.
    thread_local CellGeometry g;
    thread_local Eigen::MatrixXd G, Gw;  // n × 3·nq physical gradients, and weighted by κ det J w
    thread_local Eigen::VectorXd f;      // rhs_batch at the points
    geometry.evaluate(cell, g);
    if (with_load && problem.rhs_batch) {
      f.resize(nq);
      problem.rhs_batch(g.x, f);
      Fe.noalias() += basis.values.transpose() * g.det_w.cwiseProduct(f);
    } else if (with_load && problem.rhs) {
      for (int q = 0; q < nq; ++q)
        Fe.noalias() +=
            (g.det_w[q] * problem.rhs(g.x.row(q).transpose())) * basis.values.row(q).transpose();
    }
    if (!with_matrix) return;
    if (tensor) {
      const Eigen::Matrix3d& Ji = g.jacobian_inv[0];
      const Eigen::Matrix3d C = Ji * Ji.transpose();
      const double scale = problem.kappa_value * g.det_w[0] / rule.weights[0];  // κ det J
      const Eigen::Matrix<double, 6, 1> c = scale * (Eigen::Matrix<double, 6, 1>() << C(0, 0),
                                                     C(1, 1), C(2, 2), C(0, 1), C(0, 2), C(1, 2))
                                                        .finished();
      Ke.reshaped().noalias() = T * c;
      return;
    }
    G.resize(n, 3 * nq);
    Gw.resize(n, 3 * nq);
    for (int q = 0; q < nq; ++q) {
      const Eigen::Vector3d x = g.x.row(q).transpose();
      const double kappa = kappa_at(problem, cell, x);
      G.middleCols<3>(3 * q).noalias() = basis.gradients[q] * g.jacobian_inv[q];
      Gw.middleCols<3>(3 * q) = (g.det_w[q] * kappa) * G.middleCols<3>(3 * q);
    }
    Ke.noalias() = Gw * G.transpose();  // Σ_q κ det J w ∇φ ∇φᵀ as one matrix product
  };
  const std::vector<char> active =
      parts.rows ? cells_touching(space.cell_dofs, *parts.rows) : std::vector<char>();
  assemble_cells(mesh.num_cells(), n, kernel, pattern.get(), space.cell_dofs, 1,
                 with_matrix ? system.K.valuePtr() : nullptr, with_load ? &system.F : nullptr,
                 parts.rows ? &active : nullptr);
  if (kept_out) {
    kept_out->pattern = pattern;
    kept_out->K = system.K;
  }
  if (!with_load) {
    add_robin(mesh, space, problem, parts, system);
    return system;
  }

  system.F_volume = system.F;
  system.rhs_integral = system.F.sum();
  // Neumann data: evaluated at every face point in parallel (the flux may be expensive, e.g. a
  // point location through φ⁻¹), then summed serially in point order.
  const int face_degree = default_quadrature_degree(p, mesh.order, QuadratureUse::mass);
  for (const auto& bc : problem.neumann) {
    const FacePoints points = face_points(mesh, space, bc.faces, face_degree);
    std::vector<double> flux(points.size(), 0.0);
    const std::vector<char> used =
        evaluate_at_face_points(points, bc.where, [&](int k, const Eigen::Vector3d& x) {
          flux[std::size_t(k)] = bc.flux(x, points.normal.row(k).transpose());
        });
    for (int k = 0; k < points.size(); ++k) {
      if (!used[k]) continue;
      const double g = flux[k] * points.ds_w[k];
      const double* phi = points.basis.row(points.basis_row[k]).data();
      for (int a = 0; a < n; ++a) system.F[space.cell_dofs(points.cell[k], a)] += g * phi[a];
    }
  }
  system.flux_integral = system.F.sum() - system.rhs_integral;
  add_robin(mesh, space, problem, parts, system);
  return system;
}

}  // namespace

AssembledSystem assemble_poisson(const LagrangeMesh& mesh, const FunctionSpace& space,
                                 const PoissonProblem& problem) {
  return assemble_poisson_kept(mesh, space, problem, nullptr, nullptr);
}

namespace {

/// Adds the symmetric Nitsche terms of one Dirichlet condition on its partial faces to K, F (the
/// parts assembled: K's rows, F).
void add_nitsche(const LagrangeMesh& mesh, const FunctionSpace& space,
                 const PoissonProblem& problem, const ScalarDirichlet& bc,
                 const DirichletFaceSplit& split, AssembledSystem& system,
                 const AssemblyParts& parts = {}) {
  const FacePoints& P = split.points;
  const int n = static_cast<int>(space.cell_dofs.cols());
  Eigen::MatrixXd Ke(n, n);
  Eigen::VectorXd Fe(n);
  for (int k = 0; k < P.size(); ++k) {
    if (!split.used[std::size_t(k)]) continue;
    const int cell = P.cell[k];
    const Eigen::Vector3d x = P.x.row(k).transpose();
    const Eigen::Vector3d normal = P.normal.row(k).transpose();
    const double kappa = kappa_at(problem, cell, x);
    const double h =
        nitsche_length(mesh, cell, space.boundary_faces[std::size_t(P.face[k])].opposite);
    const double beta = kappa * nitsche_penalty(space.degree, h);
    const Eigen::Map<const Eigen::VectorXd> phi(P.basis.row(P.basis_row[k]).data(), n);
    const Eigen::VectorXd dn = P.gradients[std::size_t(k)] * normal;  // ∂φ/∂n
    const double w = P.ds_w[k], g = bc.value(x);
    Ke.noalias() = (-w * kappa) * (phi * dn.transpose() + dn * phi.transpose());
    Ke.noalias() += (w * beta) * (phi * phi.transpose());
    Fe.noalias() = (w * g) * (beta * phi - kappa * dn);
    for (int a = 0; a < n; ++a) {
      const int da = space.cell_dofs(cell, a);
      if (parts.load) system.F[da] += Fe[a];
      for (int b = 0; b < n; ++b) {
        const int db = space.cell_dofs(cell, b);
        if (parts.keeps(db)) system.K.coeffRef(da, db) += Ke(a, b);
      }
    }
  }
}

}  // namespace

PoissonSolution solve_poisson(const LagrangeMesh& mesh, const FunctionSpace& space,
                              const PoissonProblem& problem, const LinearSolverOptions& solver) {
  PoissonSolution result;
  result.dofs = space.num_dofs;
  AssembledSystem system;
  // Several MPI ranks: K is assembled by rows, one rank's at a time, inside the distributed solve
  // (solve_constrained_by_rows); here only F. Not for pure Neumann problems (their kernel is
  // handled on the whole matrix). A cache is not used then: the ranks set their KSP up for every
  // solve anyway, and keeping the stiffness would keep the whole matrix on rank 0 (the load
  // cases and the shifted passes of a run assemble their rows again).
  bool by_rows = distributed::active() && !(problem.dirichlet.empty() && problem.robin.empty());
  {
    ScopedTimer t(result.timings, "assembly");
    // The cell stiffness kept by an earlier solve sharing the solver's cache, if it is this one's.
    const int quadrature = stiffness_quadrature(mesh, space, problem);
    std::shared_ptr<KeptPoissonStiffness> kept;
    if (by_rows) {
      system = assemble_poisson_kept(mesh, space, problem, nullptr, nullptr, k_load_only);
    } else if (solver.factorization_cache) {
      kept = std::dynamic_pointer_cast<KeptPoissonStiffness>(
          assembly_cache_slot(*solver.factorization_cache));
      if (kept && !kept->matches(mesh, space, problem, quadrature)) kept.reset();
    }
    if (kept) {
      count_assembly(*solver.factorization_cache, true);
      system = assemble_poisson_kept(mesh, space, problem, kept.get(), nullptr);
    } else if (solver.factorization_cache && !by_rows) {
      kept = std::make_shared<KeptPoissonStiffness>(mesh, space, problem, quadrature);
      system = assemble_poisson_kept(mesh, space, problem, nullptr, kept.get());
      assembly_cache_slot(*solver.factorization_cache) = kept;
      count_assembly(*solver.factorization_cache, false);
    } else if (!by_rows) {
      system = assemble_poisson(mesh, space, problem);
    }
    if (by_rows && problem.dirichlet.empty() && system.robin_area == 0) {
      // Robin conditions that select no point: pure Neumann after all, on the whole matrix.
      by_rows = false;
      AssembledSystem whole = assemble_poisson_kept(mesh, space, problem, nullptr, nullptr,
                                                    AssemblyParts{true, false, nullptr});
      system.K.swap(whole.K);
    }
  }
  const Eigen::VectorXd load = system.F;  // l(v) before the Nitsche terms join F
  std::vector<DirichletFaceSplit> splits;
  {
    ScopedTimer t(result.timings, "assembly");  // the Nitsche terms
    for (const auto& bc : problem.dirichlet) {
      splits.push_back(
          split_dirichlet_faces(mesh, space, bc.faces, bc.where, problem.partial_dirichlet));
      add_nitsche(mesh, space, problem, bc, splits.back(), system,
                  by_rows ? k_load_only : AssemblyParts{});
      result.nitsche_faces += splits.back().partial_faces;
    }
  }
  Constraints constraints;
  constraints.fixed.assign(space.num_dofs, 0);
  constraints.values = Eigen::VectorXd::Zero(space.num_dofs);
  for (std::size_t i = 0; i < problem.dirichlet.size(); ++i) {
    const auto& bc = problem.dirichlet[i];
    for_each_boundary_dof(space, splits[i].strong, bc.where, [&](int d) {
      constraints.fixed[d] = 1;
      constraints.values[d] = bc.value(space.dof_points.row(d).transpose());
    });
  }
  result.free_dofs = space.num_dofs - constraints.num_fixed();
  result.rhs_integral = system.rhs_integral;
  result.flux_integral = system.flux_integral;
  if (problem.dirichlet.empty() && system.robin_area == 0) {
    ScopedTimer t(result.timings, "solve");
    const NullSpaceModes modes = null_space_modes(mesh, space, 1);
    result.null_space_dim = modes.size();
    result.u = solve_modulo_null_space(system.K, system.F, modes, space, solver, &result.solve,
                                       &result.compatibility);
    const LoadCompatibility& c = result.compatibility;
    if (!c.compatible())
      log::warn("pure Neumann Poisson: the data are not compatible: integral of f ",
                system.rhs_integral, " + integral of the flux g ", system.flux_integral, " = ",
                c.resultant[0], " (relative ", c.relative, " > ", k_compatibility_tolerance,
                "); solved with f minus its mean ", c.resultant[0] / modes.gram(0, 0));
    log::info("pure Neumann Poisson: solution up to a constant, reported with mean zero");
    result.load_functional = load.dot(result.u);
    result.load_functional_volume = system.F_volume.dot(result.u);
    return result;
  }
  if (by_rows) {
    distributed::RowAssembly rows;
    rows.cell_dofs = &space.cell_dofs;
    rows.nodes = space.num_dofs;
    rows.block_size = 1;
    rows.rows = [&](const std::vector<char>& dofs) {
      const AssemblyParts part{true, false, &dofs};
      AssembledSystem block = assemble_poisson_kept(mesh, space, problem, nullptr, nullptr, part);
      for (std::size_t i = 0; i < problem.dirichlet.size(); ++i)
        add_nitsche(mesh, space, problem, problem.dirichlet[i], splits[i], block, part);
      return take(block.K);
    };
    Stopwatch watch;
    result.u = solve_constrained_by_rows(rows, system.F, constraints, solver, &result.solve);
    result.timings.add("assembly", result.solve.assembly_s);
    result.timings.add("solve", watch.seconds() - result.solve.assembly_s);
  } else {
    ScopedTimer t(result.timings, "solve");
    result.u = solve_constrained(std::move(system.K), system.F, constraints, solver, &result.solve);
  }
  result.load_functional = load.dot(result.u);
  result.load_functional_volume = system.F_volume.dot(result.u);
  return result;
}

}  // namespace curvefem::fem
