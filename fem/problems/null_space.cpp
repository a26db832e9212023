#include "fem/problems/null_space.hpp"

#include <Eigen/LU>
#include <vector>

#include "fem/assembly/element_geometry.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"

namespace curvefem::fem {
namespace {

/// Levi-Civita symbol ε_ijk.
double levi_civita(int i, int j, int k) {
  return static_cast<double>((i - j) * (j - k) * (k - i)) / 2.0;
}

/// Component i of mode k at y = x − c.
double mode_value(int components, int k, int i, const Eigen::Vector3d& y) {
  if (components == 1 || k < 3) return k == i ? 1.0 : 0.0;
  double v = 0.0;  // (e_a × y)_i = Σ_b ε_iab y_b
  for (int b = 0; b < 3; ++b) v += levi_civita(i, k - 3, b) * y[b];
  return v;
}

/// ∫ over the mesh of Σ_q w(x_q) visit(cell, q, x): calls visit at every quadrature point of a
/// rule of `degree`, with the cell's geometry and the basis tabulation at its points.
template <class Visit>
void for_each_point(const LagrangeMesh& mesh, int p, int degree, Visit&& visit) {
  const QuadratureRule& rule = tetrahedron_quadrature(degree);
  const GeometryEvaluator geometry(mesh, rule.points, rule.weights);
  const ReferenceTabulation basis = tabulate(CellKind::tetrahedron, p, rule.points);
  CellGeometry g;
  for (int cell = 0; cell < mesh.num_cells(); ++cell) {
    geometry.evaluate(cell, g);
    for (int q = 0; q < geometry.num_points(); ++q) visit(cell, q, g, basis);
  }
}

}  // namespace

void NullSpaceModes::evaluate(const Eigen::VectorXd& theta, const Eigen::Vector3d& x, double* value,
                              double* gradient) const {
  const Eigen::Vector3d y = x - center;
  for (int i = 0; i < components; ++i) {
    value[i] = 0.0;
    for (int k = 0; k < size(); ++k) value[i] += theta[k] * mode_value(components, k, i, y);
    if (!gradient) continue;
    for (int j = 0; j < 3; ++j) {  // ∂_j (e_a × y)_i = ε_iaj
      double d = 0.0;
      for (int k = 3; k < size(); ++k) d += theta[k] * levi_civita(i, k - 3, j);
      gradient[3 * i + j] = d;
    }
  }
}

NullSpaceModes null_space_modes(const LagrangeMesh& mesh, const FunctionSpace& space,
                                int components) {
  CF_VERIFY(components == 1 || components == 3, "null-space modes: 1 or 3 components");
  NullSpaceModes modes;
  modes.components = components;
  const int c = components, m = c == 1 ? 1 : 6, nd = space.num_dofs;
  modes.center = space.dof_points.colwise().mean().transpose();
  // ∫ φ_i and ∫ (x − c)_b φ_i, from which every moment follows.
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(nd, 4);
  const int n = static_cast<int>(space.cell_dofs.cols());
  for_each_point(mesh, space.degree,
                 default_quadrature_degree(space.degree, mesh.order, QuadratureUse::mass),
                 [&](int cell, int q, const CellGeometry& g, const ReferenceTabulation& basis) {
                   const Eigen::Vector3d y = g.x.row(q).transpose() - modes.center;
                   for (int a = 0; a < n; ++a) {
                     const double v = g.det_w[q] * basis.values(q, a);
                     const int d = space.cell_dofs(cell, a);
                     w(d, 0) += v;
                     for (int b = 0; b < 3; ++b) w(d, 1 + b) += v * y[b];
                   }
                 });
  modes.nodal.resize(static_cast<Eigen::Index>(c) * nd, m);
  modes.moments.resize(static_cast<Eigen::Index>(c) * nd, m);
  for (int d = 0; d < nd; ++d) {
    const Eigen::Vector3d y = space.dof_points.row(d).transpose() - modes.center;
    for (int k = 0; k < m; ++k)
      for (int i = 0; i < c; ++i) {
        modes.nodal(c * d + i, k) = mode_value(c, k, i, y);
        double b = k < 3 || c == 1 ? (k == i ? w(d, 0) : 0.0) : 0.0;
        if (c == 3 && k >= 3)
          for (int j = 0; j < 3; ++j) b += levi_civita(i, k - 3, j) * w(d, 1 + j);
        modes.moments(c * d + i, k) = b;
      }
  }
  modes.gram = modes.moments.transpose() * modes.nodal;
  modes.gram = 0.5 * (modes.gram + modes.gram.transpose()).eval();
  return modes;
}

LoadCompatibility load_compatibility(const NullSpaceModes& modes, const FunctionSpace& space,
                                     const Eigen::VectorXd& F) {
  const int c = modes.components;
  CF_VERIFY(F.size() == modes.nodal.rows(), "load and null-space modes differ in size");
  LoadCompatibility out;
  out.resultant = modes.nodal.transpose() * F;
  out.center = modes.center;
  for (int d = 0; d < space.num_dofs; ++d) {
    const double f = F.segment(static_cast<Eigen::Index>(c) * d, c).norm();
    out.force_scale += f;
    out.moment_scale += (space.dof_points.row(d).transpose() - modes.center).norm() * f;
  }
  auto ratio = [](double a, double s) { return s > 0 ? a / s : 0.0; };
  out.relative = ratio(out.resultant.head(c).norm(), out.force_scale);
  if (c == 3)
    out.relative = std::max(out.relative, ratio(out.resultant.tail(3).norm(), out.moment_scale));
  return out;
}

void make_compatible(const NullSpaceModes& modes, Eigen::VectorXd& F) {
  const Eigen::VectorXd theta = modes.gram.partialPivLu().solve(modes.nodal.transpose() * F);
  F -= modes.moments * theta;
}

void remove_null_component(const NullSpaceModes& modes, Eigen::VectorXd& u) {
  const Eigen::VectorXd theta = modes.gram.partialPivLu().solve(modes.moments.transpose() * u);
  u -= modes.nodal * theta;
}

Eigen::VectorXd solve_modulo_null_space(const SparseMatrix& K, Eigen::VectorXd F,
                                        const NullSpaceModes& modes, const FunctionSpace& space,
                                        const LinearSolverOptions& options, LinearSolveInfo* info,
                                        LoadCompatibility* compatibility) {
  CF_VERIFY(K.rows() == modes.nodal.rows(), "system and null-space modes differ in size");
  const SparseMatrix K_abs = K.cwiseAbs();
  for (int k = 0; k < modes.size(); ++k) {
    const double scale = (K_abs * modes.nodal.col(k).cwiseAbs()).norm();
    const double leak = (K * modes.nodal.col(k)).norm();
    if (leak > 1e-8 * scale)
      log::warn("null-space mode ", k,
                " is not in the discrete space (relative |K r| = ", leak / scale,
                "; mesh order above the degree?): the system is not singular but "
                "ill-conditioned, and the solution is approximate");
  }
  const LoadCompatibility c = load_compatibility(modes, space, F);
  if (compatibility) *compatibility = c;
  make_compatible(modes, F);
  LinearSolverOptions o = options;
  o.null_space = modes.nodal;
  Eigen::VectorXd u = solve_spd(K, F, o, info);
  remove_null_component(modes, u);
  return u;
}

ErrorNorms compute_errors_modulo_null_space(const LagrangeMesh& mesh, const FunctionSpace& space,
                                            const NullSpaceModes& modes, const Eigen::VectorXd& u,
                                            const ExactValue& exact,
                                            const ExactGradient& exact_gradient,
                                            Eigen::VectorXd* offset, int quadrature_degree) {
  const int c = modes.components, m = modes.size();
  CF_VERIFY(u.size() == modes.nodal.rows(), "field size mismatch");
  const int degree = quadrature_degree >= 0 ? quadrature_degree
                                            : default_quadrature_degree(space.degree, mesh.order,
                                                                        QuadratureUse::error);
  // ∫ r_k · u (exact solution) by quadrature; ∫ r_k · u_h = Bᵀ u_h.
  Eigen::VectorXd exact_moments = Eigen::VectorXd::Zero(m);
  Eigen::VectorXd ue(c);
  for_each_point(mesh, space.degree, degree,
                 [&](int, int q, const CellGeometry& g, const ReferenceTabulation&) {
                   const Eigen::Vector3d x = g.x.row(q).transpose();
                   exact(x, ue.data());
                   for (int k = 0; k < m; ++k)
                     for (int i = 0; i < c; ++i)
                       exact_moments[k] +=
                           g.det_w[q] * ue[i] * mode_value(c, k, i, x - modes.center);
                 });
  const Eigen::VectorXd theta =
      modes.gram.partialPivLu().solve(modes.moments.transpose() * u - exact_moments);
  if (offset) *offset = theta;
  const NullSpaceModes* r = &modes;
  return compute_errors(
      mesh, space, u, c,
      [&exact, r, &theta](const Eigen::Vector3d& x, double* v) {
        double shift[3];
        exact(x, v);
        r->evaluate(theta, x, shift);
        for (int i = 0; i < r->components; ++i) v[i] += shift[i];
      },
      [&exact_gradient, r, &theta](const Eigen::Vector3d& x, double* g) {
        double shift[3], dshift[9];
        exact_gradient(x, g);
        r->evaluate(theta, x, shift, dshift);
        for (int i = 0; i < 3 * r->components; ++i) g[i] += dshift[i];
      },
      degree);
}

}  // namespace curvefem::fem
