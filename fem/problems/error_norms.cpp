#include "fem/problems/error_norms.hpp"

#include <tbb/parallel_for.h>

#include <array>
#include <cmath>

#include "fem/assembly/element_geometry.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/error.hpp"

namespace curvefem::fem {

ErrorNorms compute_errors(const LagrangeMesh& mesh, const FunctionSpace& space,
                          const Eigen::VectorXd& u, int c, const ExactValue& exact,
                          const ExactGradient& exact_gradient, int quadrature_degree) {
  // Point by point into the batch's layout.
  return compute_errors(
      mesh, space, u, c,
      [&](const Eigen::MatrixXd& x, Eigen::MatrixXd& values, Eigen::MatrixXd& gradients) {
        Eigen::VectorXd v(c);
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> g(c, 3);
        for (Eigen::Index q = 0; q < x.rows(); ++q) {
          const Eigen::Vector3d p = x.row(q).transpose();
          exact(p, v.data());
          exact_gradient(p, g.data());
          values.row(q) = v.transpose();
          for (int i = 0; i < c; ++i)
            for (int j = 0; j < 3; ++j) gradients(q, 3 * i + j) = g(i, j);
        }
      },
      quadrature_degree);
}

ErrorNorms compute_errors(const LagrangeMesh& mesh, const FunctionSpace& space,
                          const Eigen::VectorXd& u, int c, const ExactBatch& exact,
                          int quadrature_degree) {
  CF_VERIFY(u.size() == static_cast<Eigen::Index>(space.num_dofs) * c, "field size mismatch");
  const int degree = quadrature_degree >= 0 ? quadrature_degree
                                            : default_quadrature_degree(space.degree, mesh.order,
                                                                        QuadratureUse::error);
  const QuadratureRule& rule = tetrahedron_quadrature(degree);
  const GeometryEvaluator geometry(mesh, rule.points, rule.weights);
  const ReferenceTabulation basis = tabulate(CellKind::tetrahedron, space.degree, rule.points);
  const int n = static_cast<int>(space.cell_dofs.cols());
  const int nq = geometry.num_points();
  using Sums = std::array<double, 4>;
  // Fixed-size chunks reduced in order: deterministic for any thread count.
  const int chunk = 256;
  const int chunks = (mesh.num_cells() + chunk - 1) / chunk;
  std::vector<Sums> partial(chunks, Sums{0, 0, 0, 0});
  tbb::parallel_for(0, chunks, [&](int k) {
    CellGeometry g;
    Eigen::MatrixXd U(n, c), UH(nq, c), UE(nq, c), GE(nq, 3 * c);
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::ColMajor, 3, 3> ref(c, 3), guh(c, 3);
    Sums s{0, 0, 0, 0};
    for (int cell = k * chunk; cell < std::min(mesh.num_cells(), (k + 1) * chunk); ++cell) {
      geometry.evaluate(cell, g);
      for (int a = 0; a < n; ++a)
        for (int i = 0; i < c; ++i) U(a, i) = u[space.cell_dofs(cell, a) * c + i];
      exact(g.x, UE, GE);
      UH.noalias() = basis.values * U;  // n_q × c
      for (int q = 0; q < nq; ++q) {
        ref.noalias() = U.transpose() * basis.gradients[q];  // c × 3, ∂u_h/∂ξ
        guh.noalias() = ref * g.jacobian_inv[q];             // c × 3, ∂u_h/∂x
        double e0 = 0, e1 = 0, n0 = 0, n1 = 0;
        for (int i = 0; i < c; ++i) {
          const double du = UH(q, i) - UE(q, i);
          e0 += du * du;
          n0 += UE(q, i) * UE(q, i);
          for (int j = 0; j < 3; ++j) {
            const double dg = guh(i, j) - GE(q, 3 * i + j);
            e1 += dg * dg;
            n1 += GE(q, 3 * i + j) * GE(q, 3 * i + j);
          }
        }
        s[0] += g.det_w[q] * e0;
        s[1] += g.det_w[q] * e1;
        s[2] += g.det_w[q] * n0;
        s[3] += g.det_w[q] * n1;
      }
    }
    partial[k] = s;
  });
  Sums total{0, 0, 0, 0};
  for (const auto& s : partial)
    for (int i = 0; i < 4; ++i) total[i] += s[i];
  return {std::sqrt(total[0]), std::sqrt(total[1]), std::sqrt(total[2]), std::sqrt(total[3])};
}

}  // namespace curvefem::fem
