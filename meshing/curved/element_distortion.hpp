#pragma once
// Distortion of one curved Lagrange tetrahedron: how far its geometric map F (order k = 1..4,
// canonical node order of meshing/core/lagrange_nodes.hpp) is from affine, in the quantities the
// FEM error constants depend on (Ciarlet–Raviart: the estimates on a curved element carry
// ‖DF⁻¹‖ · |F|_{m}, m = 2..p + 1). Positivity (jacobian_certificate.hpp) does not bound them: a
// certified tet can carry a map whose second or third derivatives are as large as its first,
// and then a degree-p space on it approximates like a much smaller or coarser element — worse
// still when k > p, where the space does not even contain the linear functions.
//
// All quantities are taken in the reference tet (size 1) and are dimensionless, so they are the
// physical h · ‖D²F‖ / ‖DF‖ and h² · ‖D³F‖ / ‖DF‖ with h the element's size:
//   jacobian_ratio  min det J / max det J over the sample points (1 for a straight tet; ≤ 0 when
//                   det J changes sign at a sample);
//   d2              max over samples of ‖D²F(ξ)‖ · ‖DF(ξ)⁻¹‖₂, ‖D²F‖ the Frobenius norm of the
//                   3 × 3 × 3 tensor (0 for a straight tet; ~ h·κ for a tet that follows a surface
//                   of curvature κ);
//   d3              the same with D³F (0 for k ≤ 2): the cubic and quartic content of the map.
// Samples: the order-max(k, 2) lattice points (corners, edge, face and interior points) and the
// centroid. Derivatives are exact (the Lagrange basis in monomial form). An estimate, not a bound.
// Reported per tet in report.json (validation.distortion) and in mesh.vtu / volume.vtu.

#include <Eigen/Core>

namespace curvefem::meshing::curved {

struct ElementDistortion {
  double jacobian_ratio = 1;
  double d2 = 0;
  double d3 = 0;
};

/// nodes: #lattice(k) × 3 in canonical order. InputError for an order outside 1..4 or a wrong
/// node count. A singular DF at a sample gives d2 = d3 = +∞ (when D²F, D³F are not zero).
ElementDistortion element_distortion(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes);

}  // namespace curvefem::meshing::curved
