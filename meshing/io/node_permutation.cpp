#include "meshing/io/node_permutation.hpp"

#include <limits>

#include "meshing/core/error.hpp"

namespace curvefem::io::detail {

std::vector<int> match_reference_nodes(const Eigen::MatrixXd& foreign, CellKind kind, int order,
                                       double tolerance, const std::string& source) {
  const Eigen::MatrixXd canonical = lagrange_reference_nodes(kind, order);
  const int n = static_cast<int>(canonical.rows());
  const int dim = cell_dimension(kind);
  const std::string what = source + " (" +
                           (kind == CellKind::triangle ? "triangle" : "tetrahedron") +
                           " of order " + std::to_string(order) + ")";
  CF_VERIFY(foreign.rows() == n, what + ": has " + std::to_string(foreign.rows()) +
                                     " reference nodes, expected " + std::to_string(n));
  CF_VERIFY(foreign.cols() >= dim, what + ": reference coordinates have too few columns");
  std::vector<int> perm(n, -1);
  std::vector<int> used(n, -1);
  for (int i = 0; i < n; ++i) {
    for (int d = dim; d < foreign.cols(); ++d)
      CF_VERIFY(std::abs(foreign(i, d)) < tolerance,
                what + ": node " + std::to_string(i) + " leaves the reference plane");
    int best = -1;
    double best_distance = std::numeric_limits<double>::infinity();
    for (int j = 0; j < n; ++j) {
      const double distance = (foreign.row(i).head(dim) - canonical.row(j)).norm();
      if (distance < best_distance) {
        best_distance = distance;
        best = j;
      }
    }
    CF_VERIFY(best_distance < tolerance, what + ": node " + std::to_string(i) +
                                             " matches no canonical node (nearest at " +
                                             std::to_string(best_distance) + ")");
    CF_VERIFY(used[best] < 0, what + ": nodes " + std::to_string(used[best]) + " and " +
                                  std::to_string(i) + " match the same canonical node " +
                                  std::to_string(best));
    used[best] = i;
    perm[i] = best;
  }
  return perm;
}

double reference_node_mismatch(const Eigen::MatrixXd& foreign, CellKind kind, int order,
                               const std::vector<int>& perm) {
  const Eigen::MatrixXd canonical = lagrange_reference_nodes(kind, order);
  const int dim = cell_dimension(kind);
  double worst = 0.0;
  for (int i = 0; i < static_cast<int>(perm.size()); ++i)
    worst = std::max(worst, (foreign.row(i).head(dim) - canonical.row(perm[i])).norm());
  return worst;
}

}  // namespace curvefem::io::detail
