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
  return compute_errors(
      mesh, space, u, c,
      [&](const Eigen::Vector3d& x, double* value, double* gradient) {
        exact(x, value);
        exact_gradient(x, gradient);
      },
      quadrature_degree);
}

ErrorNorms compute_errors(const LagrangeMesh& mesh, const FunctionSpace& space,
                          const Eigen::VectorXd& u, int c, const ExactValueGradient& exact,
                          int quadrature_degree) {
  CF_VERIFY(u.size() == static_cast<Eigen::Index>(space.num_dofs) * c, "field size mismatch");
  const int degree = quadrature_degree >= 0 ? quadrature_degree
                                            : default_quadrature_degree(space.degree, mesh.order,
                                                                        QuadratureUse::error);
  const QuadratureRule& rule = tetrahedron_quadrature(degree);
  const GeometryEvaluator geometry(mesh, rule.points, rule.weights);
  const ReferenceTabulation basis = tabulate(CellKind::tetrahedron, space.degree, rule.points);
  const int n = static_cast<int>(space.cell_dofs.cols());
  using Sums = std::array<double, 4>;
  // Fixed-size chunks reduced in order: deterministic for any thread count.
  const int chunk = 256;
  const int chunks = (mesh.num_cells() + chunk - 1) / chunk;
  std::vector<Sums> partial(chunks, Sums{0, 0, 0, 0});
  tbb::parallel_for(0, chunks, [&](int k) {
    CellGeometry g;
    Eigen::MatrixXd U(n, c);
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::ColMajor, 3, 3> ref(c, 3), guh(c, 3);
    Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 3, 1> uh(c), ue(c);
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> ge(c, 3);
    Sums s{0, 0, 0, 0};
    for (int cell = k * chunk; cell < std::min(mesh.num_cells(), (k + 1) * chunk); ++cell) {
      geometry.evaluate(cell, g);
      for (int a = 0; a < n; ++a)
        for (int i = 0; i < c; ++i) U(a, i) = u[space.cell_dofs(cell, a) * c + i];
      for (int q = 0; q < geometry.num_points(); ++q) {
        const Eigen::Vector3d x = g.x.row(q).transpose();
        uh.noalias() = U.transpose() * basis.values.row(q).transpose();
        ref.noalias() = U.transpose() * basis.gradients[q];  // c × 3, ∂u_h/∂ξ
        guh.noalias() = ref * g.jacobian_inv[q];             // c × 3, ∂u_h/∂x
        exact(x, ue.data(), ge.data());
        s[0] += g.det_w[q] * (uh - ue).squaredNorm();
        s[1] += g.det_w[q] * (guh - ge).squaredNorm();
        s[2] += g.det_w[q] * ue.squaredNorm();
        s[3] += g.det_w[q] * ge.squaredNorm();
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
