// Poisson problem −∇·(κ ∇u) = f on a curved tetrahedral mesh with strong Dirichlet, weak
// Neumann and Robin (convective) data, continuous Lagrange elements of degree p on geometry of
// order k. Without any Dirichlet or Robin condition (pure Neumann) u is determined up to a
// constant: the solution
// returned has mean zero, the data's compatibility ∫f + ∫g = 0 is checked (a warning with the
// numbers otherwise) and their mean removed before the solve (fem/problems/null_space.hpp).
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "fem/problems/boundary_conditions.hpp"
#include "fem/problems/null_space.hpp"
#include "fem/solvers/linear_solver.hpp"
#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::fem {

struct PoissonProblem {
  ScalarField kappa;         ///< empty: kappa_value everywhere
  double kappa_value = 1.0;  ///< κ where kappa and cell_kappa are empty (a constant coefficient)
  /// Optional, overrides kappa: κ per cell and point (e.g. a coefficient per region of the mesh).
  std::function<double(int cell, const Eigen::Vector3d& x)> cell_kappa;
  ScalarField rhs;  ///< empty = 0
  /// Optional, overrides rhs: the same f over a cell's quadrature points at once.
  ScalarBatchField rhs_batch;
  std::vector<ScalarDirichlet> dirichlet;
  std::vector<ScalarNeumann> neumann;
  std::vector<ScalarRobin> robin;
  int quadrature_degree = -1;  ///< -1: default_quadrature_degree(p, k, stiffness)
  /// Dirichlet faces that a condition's filter selects only in part (fem/problems/nitsche.hpp).
  PartialDirichlet partial_dirichlet = PartialDirichlet::nitsche;
};

struct PoissonSolution {
  Eigen::VectorXd u;  ///< per DOF
  int dofs = 0, free_dofs = 0;
  int nitsche_faces = 0;  ///< boundary faces with Dirichlet data imposed weakly (partial faces)
  LinearSolveInfo solve;
  Timings timings;
  /// Pure Neumann: 1 (constants removed, ∫u_h = 0), else 0.
  int null_space_dim = 0;
  LoadCompatibility compatibility;                 ///< pure Neumann: resultant = (∫f + ∫g)
  double rhs_integral = 0.0, flux_integral = 0.0;  ///< ∫f and ∫g as assembled (Σ of F's parts)
  /// The load functional at the solution, an integral QoI (issue 22): l(u_h) = ∫f u_h + ∫g u_h
  /// (Neumann) + ∫h u∞ u_h (Robin), the assembled load vector before any Dirichlet or Nitsche
  /// term times u_h, with the data as given (pure Neumann: u_h of mean zero). With homogeneous
  /// Dirichlet data it is the compliance a(u_h, u_h); for smooth data it converges like h^2p.
  /// A condition whose filter cuts faces integrates its data by an indicator at the quadrature
  /// points, which costs the boundary part O(h) accuracy at the cut; the volume part ∫f u_h has
  /// no such term.
  double load_functional = 0.0;
  double load_functional_volume = 0.0;  ///< its part ∫f u_h
};

/// Assembled stiffness K (with the Robin terms ∫ h u v) and load F (before Dirichlet elimination).
struct AssembledSystem {
  SparseMatrix K;
  Eigen::VectorXd F;
  Eigen::VectorXd F_volume;    ///< F's volume part (∫f φ_i)
  double rhs_integral = 0.0;   ///< Σ of F's volume part = ∫f (by quadrature)
  double flux_integral = 0.0;  ///< Σ of F's Neumann part = ∫g
  double robin_area = 0.0;     ///< ∫ 1 over the Robin conditions' points (by quadrature)

  AssembledSystem() = default;
  AssembledSystem(const AssembledSystem&) = default;
  AssembledSystem& operator=(const AssembledSystem&) = default;
  // Moves hand K's storage over (Eigen's SparseMatrix has no moves of its own and would copy:
  // fem/solvers/linear_solver.hpp).
  AssembledSystem(AssembledSystem&& o) noexcept { *this = std::move(o); }
  AssembledSystem& operator=(AssembledSystem&& o) noexcept {
    K.swap(o.K);
    F = std::move(o.F);
    F_volume = std::move(o.F_volume);
    rhs_integral = o.rhs_integral;
    flux_integral = o.flux_integral;
    robin_area = o.robin_area;
    return *this;
  }
};

AssembledSystem assemble_poisson(const LagrangeMesh& mesh, const FunctionSpace& space,
                                 const PoissonProblem& problem);

PoissonSolution solve_poisson(const LagrangeMesh& mesh, const FunctionSpace& space,
                              const PoissonProblem& problem, const LinearSolverOptions& solver);

}  // namespace curvefem::fem
