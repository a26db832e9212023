#include "fem/problems/elasticity.hpp"

#include <Eigen/LU>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <sstream>
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

struct Setup {
  const QuadratureRule* rule;
  GeometryEvaluator geometry;
  ReferenceTabulation basis;
  std::unique_ptr<const SparsePattern> pattern;  ///< the whole matrix's (unless left out)
  int n;
  Setup(const LagrangeMesh& mesh, const FunctionSpace& space, int degree, bool with_pattern = true)
      : rule(&tetrahedron_quadrature(degree)),
        geometry(mesh, rule->points, rule->weights),
        basis(tabulate(CellKind::tetrahedron, space.degree, rule->points)),
        pattern(with_pattern
                    ? std::make_unique<const SparsePattern>(space.cell_dofs, space.num_dofs, 3)
                    : nullptr),
        n(static_cast<int>(space.cell_dofs.cols())) {}
};

int stiffness_degree(const LagrangeMesh& mesh, const FunctionSpace& space,
                     const ElasticityProblem& problem) {
  return problem.quadrature_degree >= 0 ? problem.quadrature_degree
                                        : tetrahedron_degree_at_same_cost(default_quadrature_degree(
                                              space.degree, mesh.order, QuadratureUse::stiffness));
}

/// External load: body force (volume) and tractions (faces); `body`, if given, receives the
/// body force's part.
Eigen::VectorXd external_load(const LagrangeMesh& mesh, const FunctionSpace& space,
                              const ElasticityProblem& problem, const Setup& setup,
                              Eigen::VectorXd* body = nullptr) {
  Eigen::VectorXd F = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(space.num_dofs));
  const int n = setup.n;
  if (problem.body_force) {
    const ElementKernel kernel = [&](int cell, Eigen::MatrixXd&, Eigen::VectorXd& Fe) {
      thread_local CellGeometry g;
      setup.geometry.evaluate(cell, g);
      for (int q = 0; q < setup.geometry.num_points(); ++q) {
        const Eigen::Vector3d f = problem.body_force(g.x.row(q).transpose()) * g.det_w[q];
        for (int a = 0; a < n; ++a)
          for (int i = 0; i < 3; ++i) Fe[3 * a + i] += f[i] * setup.basis.values(q, a);
      }
    };
    assemble_cells(mesh.num_cells(), 3 * n, kernel, nullptr, space.cell_dofs, 3, nullptr, &F);
  }
  if (body) *body = F;
  // Tractions: evaluated at every face point in parallel, summed serially in point order.
  const int face_degree = default_quadrature_degree(space.degree, mesh.order, QuadratureUse::mass);
  for (const auto& bc : problem.traction) {
    const FacePoints points = face_points(mesh, space, bc.faces, face_degree);
    std::vector<Eigen::Vector3d> traction(points.size(), Eigen::Vector3d::Zero());
    const std::vector<char> used =
        evaluate_at_face_points(points, bc.where, [&](int k, const Eigen::Vector3d& x) {
          traction[std::size_t(k)] = bc.traction(x, points.normal.row(k).transpose());
        });
    for (int k = 0; k < points.size(); ++k) {
      if (!used[k]) continue;
      const Eigen::Vector3d t = traction[k] * points.ds_w[k];
      const double* phi = points.basis.row(points.basis_row[k]).data();
      for (int a = 0; a < n; ++a)
        for (int i = 0; i < 3; ++i) F[3 * space.cell_dofs(points.cell[k], a) + i] += t[i] * phi[a];
    }
  }
  return F;
}

/// Fixed unknowns and their (full-load) values; `strong`: per condition, the faces whose DOFs
/// are fixed (empty: every selected face, nodally).
Constraints dirichlet_constraints(const FunctionSpace& space, const ElasticityProblem& problem,
                                  const std::vector<DirichletFaceSplit>& strong = {}) {
  Constraints c;
  c.fixed.assign(3 * static_cast<std::size_t>(space.num_dofs), 0);
  c.values = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(space.num_dofs));
  for (std::size_t k = 0; k < problem.dirichlet.size(); ++k) {
    const auto& bc = problem.dirichlet[k];
    for_each_boundary_dof(space, strong.empty() ? bc.faces : strong[k].strong, bc.where,
                          [&](int d) {
                            const Eigen::Vector3d v = bc.value(space.dof_points.row(d).transpose());
                            for (int i = 0; i < 3; ++i)
                              if (bc.components[i])
                                c.fixed[3 * d + i] = 1, c.values[3 * d + i] = v[i];
                          });
  }
  return c;
}

/// Adds the symmetric Nitsche terms of one Dirichlet condition on its partial faces to K, F (the
/// parts assembled: K's rows, F), on the constrained components i: −(σ(u)n)ᵢ vᵢ − (σ(v)n)ᵢ
/// (uᵢ − gᵢ) + β (uᵢ − gᵢ) vᵢ.
void add_nitsche(const LagrangeMesh& mesh, const FunctionSpace& space,
                 const ElasticityProblem& problem, const VectorDirichlet& bc,
                 const DirichletFaceSplit& split, SparseMatrix& K, Eigen::VectorXd& F,
                 const AssemblyParts& parts = {}) {
  const FacePoints& P = split.points;
  const int n = static_cast<int>(space.cell_dofs.cols());
  Eigen::MatrixXd Ke(3 * n, 3 * n);
  Eigen::VectorXd Fe(3 * n);
  Eigen::MatrixXd T(3 * n, 3);  // row 3b + j: σ(φ_b e_j) n
  for (int k = 0; k < P.size(); ++k) {
    if (!split.used[std::size_t(k)]) continue;
    const int cell = P.cell[k];
    const ElasticMaterial m =
        problem.cell_material ? problem.cell_material(cell) : problem.material;
    const double lambda = m.lambda(), mu = m.mu();
    const Eigen::Vector3d x = P.x.row(k).transpose();
    const Eigen::Vector3d nrm = P.normal.row(k).transpose();
    const double h =
        nitsche_length(mesh, cell, space.boundary_faces[std::size_t(P.face[k])].opposite);
    const double beta = (lambda + 2 * mu) * nitsche_penalty(space.degree, h);
    const double* phi = P.basis.row(P.basis_row[k]).data();
    const auto& G = P.gradients[std::size_t(k)];
    for (int b = 0; b < n; ++b) {
      const Eigen::Vector3d gb = G.row(b).transpose();
      const double dn = gb.dot(nrm);
      for (int j = 0; j < 3; ++j) {  // σ(φ e_j) n = λ ∂_j φ n + μ (∂φ/∂n e_j + n_j ∇φ)
        T.row(3 * b + j) = (lambda * gb[j] * nrm + mu * nrm[j] * gb).transpose();
        T(3 * b + j, j) += mu * dn;
      }
    }
    const double w = P.ds_w[k];
    const Eigen::Vector3d g = bc.value(x);
    Ke.setZero();
    Fe.setZero();
    for (int a = 0; a < n; ++a)
      for (int i = 0; i < 3; ++i) {
        for (int b = 0; b < n; ++b)
          for (int j = 0; j < 3; ++j) {
            double v = 0;
            if (bc.components[i]) v -= phi[a] * T(3 * b + j, i);
            if (bc.components[j]) v -= phi[b] * T(3 * a + i, j);
            if (i == j && bc.components[i]) v += beta * phi[a] * phi[b];
            Ke(3 * a + i, 3 * b + j) = w * v;
          }
        double f = bc.components[i] ? beta * g[i] * phi[a] : 0.0;
        for (int j = 0; j < 3; ++j)
          if (bc.components[j]) f -= T(3 * a + i, j) * g[j];
        Fe[3 * a + i] = w * f;
      }
    for (int a = 0; a < n; ++a)
      for (int i = 0; i < 3; ++i) {
        const int row = 3 * space.cell_dofs(cell, a) + i;
        if (parts.load) F[row] += Fe[3 * a + i];
        for (int b = 0; b < n; ++b) {
          const int db = space.cell_dofs(cell, b);
          if (!parts.keeps(db)) continue;
          for (int j = 0; j < 3; ++j) K.coeffRef(row, 3 * db + j) += Ke(3 * a + i, 3 * b + j);
        }
      }
  }
}

/// A matrix assembled by rows (several MPI ranks; constraints.hpp, solve_constrained_by_rows):
/// `assemble` fills the rows of the nodes flagged, given their pattern and the cells touching them.
using RowKernel = std::function<SparseMatrix(
    const SparsePattern& pattern, const std::vector<char>& active, const std::vector<char>& nodes)>;
distributed::RowAssembly rows_of(const FunctionSpace& space, RowKernel assemble) {
  distributed::RowAssembly rows;
  rows.cell_dofs = &space.cell_dofs;
  rows.nodes = space.num_dofs;
  rows.block_size = 3;
  rows.rows = [&space, assemble = std::move(assemble)](const std::vector<char>& nodes) {
    const SparsePattern pattern(space.cell_dofs, space.num_dofs, 3, &nodes);
    return assemble(pattern, cells_touching(space.cell_dofs, nodes), nodes);
  };
  return rows;
}

void gather(const FunctionSpace& space, const Eigen::VectorXd& u, int cell, Eigen::MatrixXd& U) {
  for (int a = 0; a < U.rows(); ++a)
    for (int i = 0; i < 3; ++i) U(a, i) = u[3 * space.cell_dofs(cell, a) + i];
}

/// K of linear elasticity (no Dirichlet data, no Nitsche terms) into `K` with `pattern` (the
/// setup's, or one of some rows: then only the cells touching them, `active`, are computed).
void assemble_stiffness(const LagrangeMesh& mesh, const FunctionSpace& space,
                        const ElasticityProblem& problem, const Setup& setup,
                        const SparsePattern& pattern, SparseMatrix& K,
                        const std::vector<char>* active = nullptr) {
  const int n = setup.n;
  K = pattern.zero_matrix();
  const int nq = setup.geometry.num_points();
  // Ke(3a+i, 3b+j) = Σ_q w (λ G_ai G_bj + μ G_aj G_bi + δ_ij μ Σ_k G_ak G_bk), G = ∇φ at q.
  // With M = Σ_q w g_q g_qᵀ for the stacked gradients g_q (row i·n + a = G_ai), one matrix
  // product: Ke(3a+i, 3b+j) = λ M(in+a, jn+b) + μ M(jn+a, in+b) + δ_ij μ Σ_k M(kn+a, kn+b).
  // Straight cells: with G = B J⁻¹ (B the reference gradients), block (i, j) of M is
  // det J Σ_kl J⁻¹(k, i) J⁻¹(l, j) R_kl for the reference matrices R_kl = Σ_q w_q B_k B_lᵀ, so
  // all nine blocks are one product of the n² × 9 table R with a 9 × 9 matrix per cell instead of
  // a product over the quadrature points.
  const bool tensor = mesh.order == 1;
  Eigen::MatrixXd R;
  if (tensor) {
    R.setZero(n * n, 9);
    for (int q = 0; q < nq; ++q) {
      const auto& B = setup.basis.gradients[q];
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l)
          R.col(3 * k + l).reshaped(n, n).noalias() +=
              setup.rule->weights[q] * B.col(k) * B.col(l).transpose();
    }
  }
  const ElementKernel kernel = [&](int cell, Eigen::MatrixXd& Ke, Eigen::VectorXd&) {
    const ElasticMaterial material =
        problem.cell_material ? problem.cell_material(cell) : problem.material;
    const double lambda = material.lambda(), mu = material.mu();
    thread_local CellGeometry g;  // per-thread scratch: no allocation per cell after the first
    thread_local Eigen::MatrixXd S, Sw, M, G, blocks;
    M.resize(3 * n, 3 * n);
    setup.geometry.evaluate(cell, g);
    if (tensor) {
      const Eigen::Matrix3d& Ji = g.jacobian_inv[0];
      const double det = g.det_w[0] / setup.rule->weights[0];
      Eigen::Matrix<double, 9, 9> A;  // A((i, j), (k, l)) = det J⁻¹(k, i) J⁻¹(l, j)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l) A(3 * i + j, 3 * k + l) = det * Ji(k, i) * Ji(l, j);
      blocks.resize(n * n, 9);
      blocks.noalias() = R * A.transpose();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          M.block(i * n, j * n, n, n) = blocks.col(3 * i + j).reshaped(n, n);
    } else {
      S.resize(3 * n, nq);
      Sw.resize(3 * n, nq);
      G.resize(n, 3);
      for (int q = 0; q < nq; ++q) {
        G.noalias() = setup.basis.gradients[q] * g.jacobian_inv[q];
        for (int i = 0; i < 3; ++i) {
          S.col(q).segment(i * n, n) = G.col(i);
          Sw.col(q).segment(i * n, n) = g.det_w[q] * G.col(i);
        }
      }
      M.noalias() = Sw * S.transpose();
    }
    for (int b = 0; b < n; ++b)
      for (int j = 0; j < 3; ++j)
        for (int a = 0; a < n; ++a) {
          const double trace = M(a, b) + M(n + a, n + b) + M(2 * n + a, 2 * n + b);
          for (int i = 0; i < 3; ++i)
            Ke(3 * a + i, 3 * b + j) = lambda * M(i * n + a, j * n + b) +
                                       mu * M(j * n + a, i * n + b) + (i == j ? mu * trace : 0.0);
        }
  };
  assemble_cells(mesh.num_cells(), 3 * n, kernel, &pattern, space.cell_dofs, 3, K.valuePtr(),
                 nullptr, active);
}

/// The stiffness of one solve, with what it depends on, kept in the solver's FactorizationCache
/// (assembly_cache_slot) for the next solve on the same mesh, space, quadrature and material: the
/// re-solves of shifted boundary values and the load cases of a run. The cell_material function
/// cannot be compared: a cache is shared only by solves of one problem's coefficients (as the
/// pipeline does; the tests' caches are per problem), and a mesh is not changed while a cache
/// holds its stiffness.
struct KeptStiffness : KeptOperator {
  KeptDiscretization on;
  ElasticMaterial material;
  bool per_cell;
  std::shared_ptr<const Setup> setup;
  SparseMatrix K;
  KeptStiffness(const LagrangeMesh& m, const FunctionSpace& s, const ElasticityProblem& problem,
                int q)
      : on(m, s, q),
        material(problem.material),
        per_cell(static_cast<bool>(problem.cell_material)),
        setup(std::make_shared<const Setup>(m, s, q)) {}
  bool matches(const LagrangeMesh& m, const FunctionSpace& s, const ElasticityProblem& problem,
               int q) const {
    return on.same(m, s, q) && material.E == problem.material.E &&
           material.nu == problem.material.nu &&
           per_cell == static_cast<bool>(problem.cell_material);
  }
};

}  // namespace

ElasticitySolution solve_linear_elasticity(const LagrangeMesh& mesh, const FunctionSpace& space,
                                           const ElasticityProblem& problem,
                                           const LinearSolverOptions& solver) {
  ElasticitySolution result;
  result.dofs = space.num_dofs;
  Stopwatch watch;
  const int quadrature = stiffness_degree(mesh, space, problem);
  // Several MPI ranks: K is assembled by rows, one rank's at a time, inside the distributed solve
  // (solve_constrained_by_rows); here only F. Not for traction-only problems (their kernel is
  // handled on the whole matrix). A cache is not used then: the ranks set their KSP up for every
  // solve anyway, and keeping the stiffness would keep the whole matrix on rank 0 (the load
  // cases and the shifted passes of a run assemble their rows again).
  const bool by_rows = distributed::active() && !problem.dirichlet.empty();
  // The stiffness kept by an earlier solve sharing the solver's cache, if it is this one's.
  std::shared_ptr<KeptStiffness> kept;
  std::shared_ptr<const Setup> row_setup;  // by rows: the tables, without the whole pattern
  if (by_rows) {
    row_setup = std::make_shared<const Setup>(mesh, space, quadrature, /*with_pattern=*/false);
  } else if (solver.factorization_cache) {
    kept =
        std::dynamic_pointer_cast<KeptStiffness>(assembly_cache_slot(*solver.factorization_cache));
    if (kept && !kept->matches(mesh, space, problem, quadrature)) kept.reset();
  }
  if (kept) {
    count_assembly(*solver.factorization_cache, true);
  } else if (!by_rows) {
    kept = std::make_shared<KeptStiffness>(mesh, space, problem, quadrature);
    assemble_stiffness(mesh, space, problem, *kept->setup, *kept->setup->pattern, kept->K);
    if (solver.factorization_cache) {
      assembly_cache_slot(*solver.factorization_cache) = kept;
      count_assembly(*solver.factorization_cache, false);
    }
  }
  const Setup& setup = by_rows ? *row_setup : *kept->setup;
  // A copy where the cache keeps it for the next solve; otherwise the assembled matrix itself.
  SparseMatrix K = by_rows ? SparseMatrix() : solver.factorization_cache ? kept->K : take(kept->K);
  Eigen::VectorXd body;
  Eigen::VectorXd F = external_load(mesh, space, problem, setup, &body);
  const Eigen::VectorXd load = F;  // l(v) before the Nitsche terms join F
  std::vector<DirichletFaceSplit> splits;
  for (const auto& bc : problem.dirichlet) {
    splits.push_back(
        split_dirichlet_faces(mesh, space, bc.faces, bc.where, problem.partial_dirichlet));
    add_nitsche(mesh, space, problem, bc, splits.back(), K, F,
                by_rows ? k_load_only : AssemblyParts{});
    result.nitsche_faces += splits.back().partial_faces;
  }
  result.timings.add("assembly", watch.seconds());
  // Without a cache nothing needs the assembly's pattern and tables again (`setup` is not used
  // below this point): free them before the solver's copies and preconditioner.
  if (!solver.factorization_cache) kept.reset();
  const Constraints constraints = dirichlet_constraints(space, problem, splits);
  result.free_unknowns = static_cast<int>(F.size()) - constraints.num_fixed();
  LinearSolverOptions options = solver;
  options.block_size = 3;
  options.near_nullspace_coordinates = space.dof_points;
  if (problem.dirichlet.empty()) {
    ScopedTimer t(result.timings, "solve");
    const NullSpaceModes modes = null_space_modes(mesh, space, 3);
    result.null_space_dim = modes.size();
    result.u =
        solve_modulo_null_space(K, F, modes, space, options, &result.solve, &result.compatibility);
    const LoadCompatibility& c = result.compatibility;
    if (!c.compatible())
      log::warn(
          "linear elasticity with tractions only: the load is not in equilibrium: total "
          "force (",
          c.resultant.head<3>().transpose(), "), total moment about (", c.center.transpose(), ") (",
          c.resultant.tail<3>().transpose(), "), relative ", c.relative, " > ",
          k_compatibility_tolerance, " (force scale ", c.force_scale, ", moment scale ",
          c.moment_scale, "); its rigid part is removed before the solve");
    result.load_functional = load.dot(result.u);
    result.load_functional_volume = body.dot(result.u);
    return result;
  }
  if (by_rows) {
    const distributed::RowAssembly rows =
        rows_of(space, [&](const SparsePattern& pattern, const std::vector<char>& active,
                           const std::vector<char>& nodes) {
          SparseMatrix block;
          assemble_stiffness(mesh, space, problem, *row_setup, pattern, block, &active);
          Eigen::VectorXd unused;
          for (std::size_t i = 0; i < problem.dirichlet.size(); ++i)
            add_nitsche(mesh, space, problem, problem.dirichlet[i], splits[i], block, unused,
                        AssemblyParts{true, false, &nodes});
          return block;  // NRVO (a copy at worst: linear_solver.hpp)
        });
    Stopwatch solve_watch;
    result.u = solve_constrained_by_rows(rows, F, constraints, options, &result.solve);
    result.timings.add("assembly", result.solve.assembly_s);
    result.timings.add("solve", solve_watch.seconds() - result.solve.assembly_s);
  } else {
    ScopedTimer t(result.timings, "solve");
    result.u = solve_constrained(std::move(K), F, constraints, options, &result.solve);
  }
  result.load_functional = load.dot(result.u);
  result.load_functional_volume = body.dot(result.u);
  return result;
}

namespace {

struct NeoHookeanState {
  SparseMatrix K;
  Eigen::VectorXd internal;  ///< ∂(strain energy)/∂u
  double strain_energy = 0.0;
  bool valid = true;  ///< false if det F ≤ 0 somewhere
};

/// The residual and energy over every cell, and with_matrix the tangent (the setup's pattern);
/// or, given `rows` (a pattern of some nodes' rows) and `active` (the cells touching them), the
/// tangent's rows alone (internal and strain_energy then cover those cells only).
NeoHookeanState assemble_neo_hookean(const Setup& setup, const LagrangeMesh& mesh,
                                     const FunctionSpace& space, const ElasticityProblem& problem,
                                     const Eigen::VectorXd& u, bool with_matrix,
                                     const SparsePattern* rows = nullptr,
                                     const std::vector<char>* active = nullptr) {
  const int n = setup.n;
  NeoHookeanState s;
  s.internal = Eigen::VectorXd::Zero(u.size());
  const SparsePattern* pattern = rows ? rows : setup.pattern.get();
  if (with_matrix) s.K = pattern->zero_matrix();
  std::vector<double> energy(mesh.num_cells(), 0.0);
  std::atomic<bool> valid{true};
  // Tangent: Ke(3a+i, 3b+j) = Σ_q w [μ δij (G Gᵀ)(a,b) + c1 H(a,j) H(b,i) + λ H(a,i) H(b,j)]
  // with G the physical basis gradients, H = G F⁻¹ and c1 = μ − λ ln J. The three sums are
  // products of per-point rows stacked over the quadrature points (h_q = H row-major, one row per
  // point): Σ λw h hᵀ = Hsᵀ Hl, Σ c1 w h hᵀ = Hsᵀ Hc whose 3×3 blocks are transposed, and
  // Σ μ w G Gᵀ = Gsᵀ Gm — three matrix products per cell instead of a loop over 9n² entries at
  // every point.
  const ElementKernel kernel = [&](int cell, Eigen::MatrixXd& Ke, Eigen::VectorXd& Re) {
    const ElasticMaterial material =
        problem.cell_material ? problem.cell_material(cell) : problem.material;
    const double lambda = material.lambda(), mu = material.mu();
    thread_local CellGeometry g;  // per-thread scratch
    thread_local Eigen::MatrixXd U, G, H, GP, Hs, Hl, Hc, Gs, Gm, Y, GG;
    const int Q = setup.geometry.num_points();
    U.resize(n, 3);
    G.resize(n, 3);
    H.resize(n, 3);
    if (with_matrix) {
      Hs.resize(Q, 3 * n);
      Hl.resize(Q, 3 * n);
      Hc.resize(Q, 3 * n);
      Gs.resize(3 * Q, n);
      Gm.resize(3 * Q, n);
    }
    setup.geometry.evaluate(cell, g);
    gather(space, u, cell, U);
    double e = 0.0;
    for (int q = 0; q < Q; ++q) {
      G.noalias() = setup.basis.gradients[q] * g.jacobian_inv[q];
      const Eigen::Matrix3d F = Eigen::Matrix3d::Identity() + U.transpose() * G;
      const double J = F.determinant();
      if (!(J > 0.0)) {
        valid = false;
        return;
      }
      const Eigen::Matrix3d Finv = F.inverse();
      const double lnJ = std::log(J);
      const double w = g.det_w[q];
      e += w *
           (0.5 * mu * ((F.transpose() * F).trace() - 3.0) - mu * lnJ + 0.5 * lambda * lnJ * lnJ);
      const Eigen::Matrix3d P = mu * (F - Finv.transpose()) + lambda * lnJ * Finv.transpose();
      GP.noalias() = G * P.transpose();  // (a, i) = Σ_k P_ik G_ak
      for (int a = 0; a < n; ++a)
        for (int i = 0; i < 3; ++i) Re[3 * a + i] += w * GP(a, i);
      if (!with_matrix) continue;
      H.noalias() = G * Finv;
      const double c1 = mu - lambda * lnJ;
      for (int a = 0; a < n; ++a)
        for (int i = 0; i < 3; ++i) {
          Hs(q, 3 * a + i) = H(a, i);
          Hl(q, 3 * a + i) = lambda * w * H(a, i);
          Hc(q, 3 * a + i) = c1 * w * H(a, i);
        }
      Gs.middleRows(3 * q, 3) = G.transpose();
      Gm.middleRows(3 * q, 3) = (mu * w) * G.transpose();
    }
    if (with_matrix) {
      Ke.noalias() += Hs.transpose() * Hl;
      Y.noalias() = Hs.transpose() * Hc;
      GG.noalias() = Gs.transpose() * Gm;
      for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
          Ke.block<3, 3>(3 * a, 3 * b) += Y.block<3, 3>(3 * a, 3 * b).transpose();
          for (int i = 0; i < 3; ++i) Ke(3 * a + i, 3 * b + i) += GG(a, b);
        }
    }
    energy[cell] = e;
  };
  assemble_cells(mesh.num_cells(), 3 * n, kernel, pattern, space.cell_dofs, 3,
                 with_matrix ? s.K.valuePtr() : nullptr, &s.internal, active);
  s.valid = valid;
  if (!s.valid) {
    release(s.K);  // a partial tangent is not handed out
    s.strain_energy = std::numeric_limits<double>::infinity();
    return s;
  }
  for (double e : energy) s.strain_energy += e;
  return s;
}

double free_norm(const Eigen::VectorXd& r, const Constraints& c) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < r.size(); ++i)
    if (!c.fixed[i]) sum += r[i] * r[i];
  return std::sqrt(sum);
}

}  // namespace

ElasticitySolution solve_neo_hookean(const LagrangeMesh& mesh, const FunctionSpace& space,
                                     const ElasticityProblem& problem,
                                     const LinearSolverOptions& solver,
                                     const NewtonOptions& newton) {
  if (newton.load_steps < 1) throw InputError("load_steps must be at least 1");
  ElasticitySolution result;
  result.dofs = space.num_dofs;
  // Several MPI ranks: each Newton step's tangent is assembled by rows inside the distributed
  // solve (solve_constrained_by_rows), so the whole pattern is not built.
  const bool by_rows = distributed::active();
  const Setup setup(mesh, space, stiffness_degree(mesh, space, problem), !by_rows);
  Eigen::VectorXd f_body;
  const Eigen::VectorXd f_ext = external_load(mesh, space, problem, setup, &f_body);
  const Constraints full = dirichlet_constraints(space, problem);
  result.free_unknowns = static_cast<int>(f_ext.size()) - full.num_fixed();
  if (problem.dirichlet.empty())
    throw InputError(
        "Neo-Hookean without a Dirichlet condition: rigid motions are not removed in the "
        "nonlinear solve (linear elasticity handles tractions only)");
  LinearSolverOptions options = solver;
  options.block_size = 3;
  options.near_nullspace_coordinates = space.dof_points;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(f_ext.size());
  Stopwatch watch;
  // One increment: Newton at load fraction s from the current u. Returns "" when converged, else
  // why not (u is then left wherever the iteration stopped).
  auto increment = [&](int step, double s) -> std::string {
    const Eigen::VectorXd f = s * f_ext;
    double first_residual = -1.0;
    for (int it = 0; it < newton.max_iterations; ++it) {
      NeoHookeanState state = assemble_neo_hookean(setup, mesh, space, problem, u, !by_rows);
      if (!state.valid) return "an iterate inverts an element (det F <= 0)";
      const Eigen::VectorXd R = state.internal - f;
      const double rnorm = free_norm(R, full);
      const double energy = state.strain_energy - f.dot(u);
      // Increment: fixed unknowns move to their scaled values on the first iteration of a step.
      Constraints inc = full;
      for (Eigen::Index i = 0; i < u.size(); ++i)
        inc.values[i] = full.fixed[i] ? s * full.values[i] - u[i] : 0.0;
      const bool moves_boundary = (inc.values.array().abs() > 0).any();
      if (first_residual < 0) first_residual = std::max(rnorm, 1e-300);
      result.newton.push_back({step, it, s, rnorm, 1.0, energy});
      log::debug("Neo-Hookean step ", step, " (load ", s, ") iteration ", it, ": residual ", rnorm,
                 ", energy ", energy);
      const double scale = std::max(f.norm(), first_residual);
      if (!moves_boundary && (rnorm <= newton.tolerance * scale || rnorm < 1e-13)) return "";
      Eigen::VectorXd du;
      try {
        if (by_rows) {
          const distributed::RowAssembly tangent =
              rows_of(space, [&](const SparsePattern& pattern, const std::vector<char>& active,
                                 const std::vector<char>&) {
                NeoHookeanState part =
                    assemble_neo_hookean(setup, mesh, space, problem, u, true, &pattern, &active);
                return take(part.K);
              });
          du = solve_constrained_by_rows(tangent, -R, inc, options, &result.solve);
        } else {
          du = solve_constrained(state.K, -R, inc, options, &result.solve);
        }
      } catch (const SolverError& e) {
        return std::string("the linear solve failed: ") + e.what();
      }
      // Backtracking: stay valid; decrease the energy (Armijo) unless the boundary moved.
      double alpha = 1.0;
      const double slope = R.dot(du);
      for (int k = 0; k < 30; ++k, alpha *= 0.5) {
        const Eigen::VectorXd trial = u + alpha * du;
        const NeoHookeanState t = assemble_neo_hookean(setup, mesh, space, problem, trial, false);
        if (!t.valid) continue;
        const double e = t.strain_energy - f.dot(trial);
        if (moves_boundary || e <= energy + 1e-4 * alpha * slope) break;
        // Near the solution the energy decrease drowns in round-off: accept a step that reduces
        // the residual instead.
        if (free_norm(t.internal - f, full) <= (1.0 - 1e-4 * alpha) * rnorm) break;
      }
      result.newton.back().step_length = alpha;
      u += alpha * du;
      if (alpha == 1.0)  // land exactly on the prescribed values (no round-off drift)
        for (Eigen::Index i = 0; i < u.size(); ++i)
          if (full.fixed[i]) u[i] = s * full.values[i];
    }
    std::ostringstream msg;
    msg << "no convergence in " << newton.max_iterations << " iterations; residuals:";
    for (const auto& r : result.newton)
      if (r.load_step == step && r.load == s) msg << ' ' << r.residual;
    return msg.str();
  };
  // The increments: load_steps equal ones, each halved (and its iterations dropped) when it
  // fails; after a halved increment converges the next one may double again, up to the nominal.
  const double nominal = 1.0 / newton.load_steps;
  double done = 0.0, size = nominal;
  for (int step = 1; done < 1.0; ++step) {
    const double s = 1.0 - done <= size * (1 + 1e-12) ? 1.0 : done + size;
    const Eigen::VectorXd u_before = u;
    const std::size_t history = result.newton.size();
    const std::string failure = increment(step, s);
    if (failure.empty()) {
      done = s;
      size = std::min(nominal, 2 * size);
      continue;
    }
    if (result.load_cuts >= newton.max_load_cuts) {
      std::ostringstream msg;
      msg << "Neo-Hookean Newton did not converge at load step " << step << " (load " << s
          << " of the full load, after " << result.load_cuts << " halved increments): " << failure;
      throw SolverError(msg.str());
    }
    log::info("Neo-Hookean: the increment to load ", s, " failed (", failure, "): halving it");
    ++result.load_cuts;
    u = u_before;
    result.newton.resize(history);
    size = 0.5 * (s - done);
    --step;
  }
  result.timings.add("newton", watch.seconds());
  result.u = u;
  result.load_functional = f_ext.dot(u);
  result.load_functional_volume = f_body.dot(u);
  return result;
}

ForceBalance force_balance(const LagrangeMesh& mesh, const FunctionSpace& space,
                           const ElasticityProblem& problem, const Eigen::VectorXd& u,
                           bool neo_hookean) {
  ForceBalance out;
  const Setup setup(mesh, space, stiffness_degree(mesh, space, problem), /*with_pattern=*/false);
  const int n = setup.n;
  // Applied load, without the basis: Σ_q f(x_q) w_q and Σ_k t(x_k) ds_k.
  if (problem.body_force) {
    CellGeometry g;
    for (int cell = 0; cell < mesh.num_cells(); ++cell) {
      setup.geometry.evaluate(cell, g);
      for (int q = 0; q < setup.geometry.num_points(); ++q)
        out.applied += problem.body_force(g.x.row(q).transpose()) * g.det_w[q];
    }
  }
  const int face_degree = default_quadrature_degree(space.degree, mesh.order, QuadratureUse::mass);
  for (const auto& bc : problem.traction) {
    const FacePoints points = face_points(mesh, space, bc.faces, face_degree);
    std::vector<Eigen::Vector3d> t(points.size(), Eigen::Vector3d::Zero());
    const std::vector<char> used =
        evaluate_at_face_points(points, bc.where, [&](int k, const Eigen::Vector3d& x) {
          t[std::size_t(k)] = bc.traction(x, points.normal.row(k).transpose());
        });
    for (int k = 0; k < points.size(); ++k)
      if (used[std::size_t(k)]) out.applied += t[std::size_t(k)] * points.ds_w[k];
  }
  // Internal force from the stress of u at the quadrature points.
  Eigen::VectorXd internal = Eigen::VectorXd::Zero(u.size());
  const ElementKernel kernel = [&](int cell, Eigen::MatrixXd&, Eigen::VectorXd& Re) {
    const ElasticMaterial m =
        problem.cell_material ? problem.cell_material(cell) : problem.material;
    const double lambda = m.lambda(), mu = m.mu();
    thread_local CellGeometry g;
    thread_local Eigen::MatrixXd U, G;
    U.resize(n, 3);
    G.resize(n, 3);
    setup.geometry.evaluate(cell, g);
    gather(space, u, cell, U);
    for (int q = 0; q < setup.geometry.num_points(); ++q) {
      G.noalias() = setup.basis.gradients[q] * g.jacobian_inv[q];
      const Eigen::Matrix3d grad = U.transpose() * G;  // ∂u_i/∂x_j
      Eigen::Matrix3d P;
      if (neo_hookean) {
        const Eigen::Matrix3d F = Eigen::Matrix3d::Identity() + grad;
        const double J = F.determinant();
        const Eigen::Matrix3d FinvT = F.inverse().transpose();
        P = mu * (F - FinvT) + lambda * std::log(J) * FinvT;
      } else {
        const Eigen::Matrix3d eps = 0.5 * (grad + grad.transpose());
        P = lambda * eps.trace() * Eigen::Matrix3d::Identity() + 2 * mu * eps;
      }
      const Eigen::MatrixXd GP = G * P.transpose();
      for (int a = 0; a < n; ++a)
        for (int i = 0; i < 3; ++i) Re[3 * a + i] += g.det_w[q] * GP(a, i);
    }
  };
  assemble_cells(mesh.num_cells(), 3 * n, kernel, nullptr, space.cell_dofs, 3, nullptr, &internal);
  const Eigen::VectorXd residual = internal - external_load(mesh, space, problem, setup);
  // Supported unknowns: the fixed ones, and every unknown of a cell with a Nitsche face.
  std::vector<DirichletFaceSplit> splits;
  if (!neo_hookean)
    for (const auto& bc : problem.dirichlet)
      splits.push_back(
          split_dirichlet_faces(mesh, space, bc.faces, bc.where, problem.partial_dirichlet));
  const Constraints c = dirichlet_constraints(space, problem, splits);
  std::vector<char> supported(c.fixed.begin(), c.fixed.end());
  for (const auto& split : splits)
    for (int k = 0; k < split.points.size(); ++k)
      if (split.used[std::size_t(k)])
        for (int a = 0; a < n; ++a)
          for (int i = 0; i < 3; ++i)
            supported[3 * std::size_t(space.cell_dofs(split.points.cell[k], a)) + i] = 1;
  for (Eigen::Index r = 0; r < residual.size(); ++r)
    if (supported[std::size_t(r)]) {
      out.reaction[r % 3] += residual[r];
      ++out.supported_unknowns;
    }
  return out;
}

Eigen::VectorXd von_mises_at_dofs(const LagrangeMesh& mesh, const FunctionSpace& space,
                                  const ElasticMaterial& material, const Eigen::VectorXd& u,
                                  const std::function<ElasticMaterial(int cell)>& cell_material) {
  const Eigen::MatrixXd ref = lagrange_reference_nodes(CellKind::tetrahedron, space.degree);
  const GeometryEvaluator geometry(mesh, ref, Eigen::VectorXd::Ones(ref.rows()));
  const ReferenceTabulation basis = tabulate(CellKind::tetrahedron, space.degree, ref);
  const int n = static_cast<int>(space.cell_dofs.cols());
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(space.num_dofs), count = sum;
  CellGeometry g;
  Eigen::MatrixXd U(n, 3), G(n, 3);
  for (int cell = 0; cell < mesh.num_cells(); ++cell) {
    const ElasticMaterial m = cell_material ? cell_material(cell) : material;
    const double lambda = m.lambda(), mu = m.mu();
    geometry.evaluate(cell, g);
    gather(space, u, cell, U);
    for (int l = 0; l < n; ++l) {
      G.noalias() = basis.gradients[l] * g.jacobian_inv[l];
      const Eigen::Matrix3d grad = U.transpose() * G;
      const Eigen::Matrix3d eps = 0.5 * (grad + grad.transpose());
      const Eigen::Matrix3d sigma =
          lambda * eps.trace() * Eigen::Matrix3d::Identity() + 2 * mu * eps;
      const Eigen::Matrix3d dev = sigma - sigma.trace() / 3.0 * Eigen::Matrix3d::Identity();
      const int d = space.cell_dofs(cell, l);
      sum[d] += std::sqrt(1.5 * dev.squaredNorm());
      count[d] += 1.0;
    }
  }
  return sum.cwiseQuotient(count);
}

}  // namespace curvefem::fem
