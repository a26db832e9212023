// Geometry of one curved tetrahedron of order k at the points of a quadrature rule: physical
// points, inverse Jacobians and |det J|·w. A non-positive det J at any point is a SolverError
// naming the element (an inverted or degenerate curved element cannot be integrated).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "fem/assembly/tabulation.hpp"
#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

struct CellGeometry {
  Eigen::MatrixXd x;                          ///< n_q × 3 physical points
  std::vector<Eigen::Matrix3d> jacobian_inv;  ///< per point, J^{-1}
  Eigen::VectorXd det_w;                      ///< per point, det J · weight
};

class GeometryEvaluator {
 public:
  /// `points`, `weights`: the quadrature rule on the reference tetrahedron.
  GeometryEvaluator(const LagrangeMesh& mesh, const Eigen::MatrixXd& points,
                    const Eigen::VectorXd& weights);
  void evaluate(int cell, CellGeometry& out) const;
  int num_points() const { return static_cast<int>(m_weights.size()); }

 private:
  const LagrangeMesh& m_mesh;
  Eigen::VectorXd m_weights;
  ReferenceTabulation m_tab;
};

}  // namespace curvefem::fem
