// Basis values and reference gradients tabulated once at the points of a quadrature rule
// (or any reference points), reused for every cell.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "meshing/core/lagrange_nodes.hpp"

namespace curvefem::fem {

struct ReferenceTabulation {
  int degree = 1;
  Eigen::MatrixXd values;                  ///< n_points × n_basis
  std::vector<Eigen::MatrixXd> gradients;  ///< per point: n_basis × dim (reference gradients)
};

/// Tabulates the Lagrange basis of `degree` on `kind` at the rows of `points` (n × dim).
ReferenceTabulation tabulate(CellKind kind, int degree, const Eigen::MatrixXd& points);

}  // namespace curvefem::fem
