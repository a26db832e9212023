// Linear elasticity and compressible Neo-Hookean hyperelasticity on curved tetrahedra.
//
// Unknowns: displacement u, 3 per DOF (DOF-major: u[3d + i]). Materials: Young's modulus E and
// Poisson ratio ν (λ = Eν/((1+ν)(1−2ν)), μ = E/(2(1+ν))).
// Linear: σ = λ tr(ε) I + 2μ ε, −∇·σ = f, Dirichlet (per component) strong, traction weak.
// Without any Dirichlet condition (tractions only), linear elasticity is solved up to the six
// rigid motions (fem/problems/null_space.hpp): the load's rigid part is removed (a warning with
// the total force and moment when they are not zero), and u has no mean translation or rotation.
// The linear solves give GAMG the rigid-body modes of the DOF points as its near-nullspace.
// Neo-Hookean (compressible): Ψ = μ/2 (tr C − 3) − μ ln J + λ/2 (ln J)², first Piola stress
// P = μ (F − F^{-T}) + λ ln J F^{-T}; Newton with backtracking line search on the energy and load
// stepping (body force, tractions and prescribed displacements scaled by s = k/steps).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "fem/problems/boundary_conditions.hpp"
#include "fem/problems/null_space.hpp"
#include "fem/solvers/linear_solver.hpp"
#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::fem {

struct ElasticMaterial {
  double E = 1.0, nu = 0.3;
  double lambda() const { return E * nu / ((1 + nu) * (1 - 2 * nu)); }
  double mu() const { return E / (2 * (1 + nu)); }
};

struct ElasticityProblem {
  ElasticMaterial material;
  /// Optional, overrides material: the material of each cell (e.g. one per region of the mesh).
  std::function<ElasticMaterial(int cell)> cell_material;
  VectorField body_force;  ///< empty = 0
  std::vector<VectorDirichlet> dirichlet;
  std::vector<VectorNeumann> traction;
  int quadrature_degree = -1;
  /// Dirichlet faces that a condition's filter selects only in part (fem/problems/nitsche.hpp).
  /// Nodal by default: a clamp whose edge cuts coarse faces comes out too stiff by Nitsche (the
  /// face's polynomial, held near zero on part of the face, is held on all of it; fem/README.md).
  /// Nitsche: linear elasticity only; Neo-Hookean always fixes the DOFs the filter passes.
  PartialDirichlet partial_dirichlet = PartialDirichlet::nodal;
};

struct NewtonStep {
  int load_step = 0, iteration = 0;  ///< load_step: the accepted increment, from 1
  double load = 1.0;                 ///< the fraction of the full load this iteration solves for
  double residual = 0.0;             ///< ‖R(u)‖ on free unknowns
  double step_length = 1.0;
  double energy = 0.0;
};

struct ElasticitySolution {
  Eigen::VectorXd u;  ///< 3 per DOF
  int dofs = 0, free_unknowns = 0;
  int nitsche_faces = 0;  ///< boundary faces with Dirichlet data imposed weakly (linear only)
  LinearSolveInfo solve;  ///< last linear solve
  /// Linear elasticity without Dirichlet conditions: 6 (rigid motions removed), else 0.
  int null_space_dim = 0;
  LoadCompatibility compatibility;  ///< when null_space_dim > 0: total force and moment
  std::vector<NewtonStep> newton;   ///< Neo-Hookean only (the accepted increments' iterations)
  int load_cuts = 0;  ///< Neo-Hookean: increments halved (NewtonOptions::max_load_cuts)
  /// The work of the applied load on the solution, an integral QoI (issue 22): l(u_h) = ∫b·u_h
  /// + ∫t·u_h (tractions), the assembled external load vector (Neo-Hookean: at the last load
  /// step) times u_h. With homogeneous Dirichlet data and linear elasticity it is the compliance
  /// a(u_h, u_h); for smooth data it converges like h^2p.
  double load_functional = 0.0;
  double load_functional_volume = 0.0;  ///< its part ∫b·u_h (the body force's work)
  Timings timings;
};

struct NewtonOptions {
  int load_steps = 1;
  /// An increment whose Newton iteration fails (a tangent that is not positive definite, an
  /// iterate that inverts an element, or no convergence in max_iterations) is undone and tried
  /// again at half its size, at most this many times over the whole solve (0: fail at once).
  int max_load_cuts = 10;
  int max_iterations = 30;
  double tolerance =
      1e-9;  ///< on ‖R‖ relative to the first residual of the step, or absolute 1e-12·scale
};

ElasticitySolution solve_linear_elasticity(const LagrangeMesh& mesh, const FunctionSpace& space,
                                           const ElasticityProblem& problem,
                                           const LinearSolverOptions& solver);

ElasticitySolution solve_neo_hookean(const LagrangeMesh& mesh, const FunctionSpace& space,
                                     const ElasticityProblem& problem,
                                     const LinearSolverOptions& solver,
                                     const NewtonOptions& newton);

/// Equilibrium of a solution, computed from u alone (not from the solver's matrices): the total
/// applied load (body force over the cells, tractions over the faces their filters pass) and the
/// total force of the supports on the body — the internal force ∫σ(u):∇φ (linear) or ∫P(F):∇φ
/// (Neo-Hookean) minus the applied load, summed over the supported unknowns (the fixed ones and,
/// for Nitsche-imposed faces, every unknown of their cells). By partition of unity the internal
/// force sums to zero, so applied + reaction is minus the residual left at the free unknowns:
/// zero up to the solver's tolerance when the solve and the load are consistent.
struct ForceBalance {
  Eigen::Vector3d applied = Eigen::Vector3d::Zero();
  Eigen::Vector3d reaction = Eigen::Vector3d::Zero();
  int supported_unknowns = 0;
  /// ‖applied + reaction‖ / max(‖applied‖, ‖reaction‖) (0 when both vanish).
  double imbalance() const {
    const double scale = std::max(applied.norm(), reaction.norm());
    return scale > 0 ? (applied + reaction).norm() / scale : 0.0;
  }
};

ForceBalance force_balance(const LagrangeMesh& mesh, const FunctionSpace& space,
                           const ElasticityProblem& problem, const Eigen::VectorXd& u,
                           bool neo_hookean);

/// Nodal von Mises stress of the linear solution at every DOF point (averaged over cells);
/// `cell_material`, when given, overrides `material` per cell.
Eigen::VectorXd von_mises_at_dofs(
    const LagrangeMesh& mesh, const FunctionSpace& space, const ElasticMaterial& material,
    const Eigen::VectorXd& u, const std::function<ElasticMaterial(int cell)>& cell_material = {});

}  // namespace curvefem::fem
