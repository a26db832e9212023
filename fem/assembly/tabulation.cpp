#include "fem/assembly/tabulation.hpp"

#include "fem/basis/lagrange_basis.hpp"

namespace curvefem::fem {

ReferenceTabulation tabulate(CellKind kind, int degree, const Eigen::MatrixXd& points) {
  const LagrangeBasis basis(kind, degree);
  const int dim = cell_dimension(kind);
  ReferenceTabulation t;
  t.degree = degree;
  t.values.resize(points.rows(), basis.size());
  t.gradients.resize(points.rows());
  for (int q = 0; q < points.rows(); ++q) {
    Eigen::Vector3d xi = Eigen::Vector3d::Zero();
    xi.head(dim) = points.row(q).transpose().head(dim);
    t.values.row(q) = basis.values(xi).transpose();
    t.gradients[q] = basis.gradients(xi);
  }
  return t;
}

}  // namespace curvefem::fem
