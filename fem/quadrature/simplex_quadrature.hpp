// Quadrature on the reference triangle and tetrahedron: collapsed Gauss–Jacobi (Stroud conical
// product) rules exact for every polynomial of total degree ≤ `degree`, for degree 0..30.
//
// Reference simplices (as meshing/core/lagrange_nodes.hpp): triangle {x, y ≥ 0, x + y ≤ 1},
// tetrahedron {x, y, z ≥ 0, x + y + z ≤ 1}. Weights sum to the reference volume: 1/2 (triangle),
// 1/6 (tetrahedron). All points lie strictly inside, all weights are positive.
//
// Construction: the collapsed map from the unit cube (u, v, w) ∈ (0,1)^3,
//   x = u,  y = (1 − u) v,  z = (1 − u)(1 − v) w,   Jacobian (1 − u)^2 (1 − v),
// turns x^a y^b z^c into u^a (1 − u)^(b+c) · v^b (1 − v)^c · w^c, a polynomial of degree ≤ degree
// in each variable separately. n = ceil((degree + 1) / 2) Gauss–Jacobi points per direction with
// weights (1 − u)^2, (1 − v)^1, 1 integrate it exactly (2n − 1 ≥ degree). Rules have n^3 (tet) or
// n^2 (triangle) points. Gauss–Jacobi nodes and weights come from the Golub–Welsch eigenproblem
// of the Jacobi matrix, polished by Newton on the three-term recurrence.
//
// Shapes: points #q × dim (row = one point's reference coordinates), weights #q.
// Rules are built once per degree and cached; the returned references stay valid for the whole
// program, and concurrent first calls from several threads are safe.
#pragma once

#include <Eigen/Core>

namespace curvefem::fem {

/// Highest degree of exactness the rule factories accept.
constexpr int k_max_quadrature_degree = 30;

struct QuadratureRule {
  Eigen::MatrixXd points;   ///< #q × dim reference coordinates
  Eigen::VectorXd weights;  ///< #q, positive, summing to the reference volume
  int degree = 0;           ///< exact for all polynomials of total degree ≤ degree

  int size() const { return static_cast<int>(weights.size()); }
  int dimension() const { return static_cast<int>(points.cols()); }
};

/// Rule on the reference tetrahedron exact to total degree `degree` (0..k_max_quadrature_degree);
/// ceil((degree+1)/2)^3 points. InputError outside the range.
const QuadratureRule& tetrahedron_quadrature(int degree);
/// Rule on the reference triangle exact to total degree `degree`; ceil((degree+1)/2)^2 points.
const QuadratureRule& triangle_quadrature(int degree);

/// Gauss–Jacobi rule on [0, 1] for the weight (1 − t)^alpha (alpha ≥ 0): n nodes, increasing,
/// exact for polynomials of degree ≤ 2n − 1. nodes and weights are resized to n.
void gauss_jacobi_01(int n, int alpha, Eigen::VectorXd& nodes, Eigen::VectorXd& weights);

enum class QuadratureUse { stiffness, mass, error };

/// Default degree of exactness for a degree-p basis on an order-k (geometry) element.
///
/// On an order-k map F, the entries of J = DF have degree k − 1, det J degree 3(k − 1), and
/// J^{-1} = adj(J) / det J with adj(J) of degree 2(k − 1). Hence
///   mass      ∫ φ_i φ_j det J                                 polynomial of degree 2p + 3(k−1):
///             the rule 2p + 3(k − 1) is exact;
///   stiffness ∫ ∇φ_i^T adj(J) adj(J)^T ∇φ_j / det J            rational for k > 1. Exact for k = 1
///             with 2(p − 1); we take 2p + 2(k − 1) (reference note fem-and-formats §5.1, verified
///             to keep optimal rates on curved meshes for p, k ≤ 4);
///   error     ∫ (u − u_h)^2 det J with a non-polynomial u: the leading error term has degree
///             p + 1, its square 2p + 2, times det J, plus a margin of 2 → 2p + 3(k − 1) + 4; never
///             fewer than the note's verified 2p + 2k + 4. So 2p + 4 + max(2k, 3(k − 1)).
/// The result is capped at k_max_quadrature_degree. InputError if p < 1 or k < 1.
int default_quadrature_degree(int p, int k, QuadratureUse use);

}  // namespace curvefem::fem
