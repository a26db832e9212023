#include "meshing/curved/slab_nodes.hpp"

#include "meshing/core/lagrange_nodes.hpp"

namespace curvefem::meshing::curved {

namespace {
constexpr double k_xy[3][2] = {{0, 0}, {1, 0}, {0, 1}};
}  // namespace

Eigen::Vector3d patch_displacement(const std::vector<Eigen::Vector3d>& d, int order, double u,
                                   double v) {
  const Eigen::VectorXd phi =
      lagrange_shape_values(CellKind::triangle, order, Eigen::Vector3d(u, v, 0));
  Eigen::Vector3d out = Eigen::Vector3d::Zero();
  for (int i = 0; i < phi.size(); ++i) out += phi[i] * d[std::size_t(i)];
  return out;
}

Eigen::MatrixXd slab_tet_nodes(int k, const Eigen::Vector3d (&P)[4], const int (&lv)[4],
                               const int (&on_mid)[4], const std::vector<Eigen::Vector3d>& d,
                               const SlabBlend& blend, unsigned pinched) {
  auto is_pinched = [&](int j) { return ((pinched >> j) & 1u) != 0; };
  const auto& tet_lattice = lagrange_lattice(CellKind::tetrahedron, k);
  // The patch at the midpoints of the triangle's edges: mid_d[a][b], a ≠ b local vertices.
  Eigen::Vector3d mid_d[3][3];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      mid_d[a][b] = a == b ? Eigen::Vector3d::Zero()
                           : patch_displacement(d, k, 0.5 * (k_xy[a][0] + k_xy[b][0]),
                                                0.5 * (k_xy[a][1] + k_xy[b][1]));
  auto quadratic_part = [&](double u, double v) {  // d₂(u, v)
    const double mu[3] = {1 - u - v, u, v};
    return Eigen::Vector3d(4 * (mu[0] * mu[1] * mid_d[0][1] + mu[0] * mu[2] * mid_d[0][2] +
                                mu[1] * mu[2] * mid_d[1][2]));
  };
  // Values of t · d₂ at the tet's edge midpoints (0 at its corners): t is the mean of the two
  // ends' shares, the fiber point the midpoint of their triangle vertices.
  Eigen::Vector3d q[4][4];
  // A pinched corner has no share of its own: its edges take the other end's.
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      q[i][j] = (is_pinched(i)   ? double(on_mid[j])
                 : is_pinched(j) ? double(on_mid[i])
                                 : 0.5 * (on_mid[i] + on_mid[j])) *
                mid_d[lv[i]][lv[j]];
  Eigen::MatrixXd nodes(Eigen::Index(tet_lattice.size()), 3);
  for (std::size_t n = 0; n < tet_lattice.size(); ++n) {
    const auto& b = tet_lattice[n];
    double l[4];
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    double u = 0, v = 0, h = 0, rest = 0;
    for (int j = 0; j < 4; ++j) {
      l[j] = double(b[j]) / k;
      x += l[j] * P[j];
      u += l[j] * k_xy[lv[j]][0];
      v += l[j] * k_xy[lv[j]][1];
      if (is_pinched(j)) continue;
      h += l[j] * on_mid[j];
      rest += l[j];
    }
    // The share of the middle corners among the corners that are not pinched: a pinched corner
    // is base and middle at once, so a node's share must not depend on which of the two the tet
    // names (the fiber there has length 0 and the patch displacement is 0).
    if (pinched != 0u) h = rest > 0 ? h / rest : 0.0;
    if (h <= 0) {
      nodes.row(Eigen::Index(n)) = x.transpose();
      continue;
    }
    // The triangle vertices the node's corners stand above: two of them put it on the side quad
    // over the edge opposite the third.
    bool above[3] = {false, false, false};
    for (int j = 0; j < 4; ++j) above[lv[j]] = above[lv[j]] || b[j] > 0;
    const int count = above[0] + above[1] + above[2];
    const bool low = count == 3   ? blend.face
                     : count == 2 ? blend.edge[!above[0]   ? 0
                                               : !above[1] ? 1
                                                           : 2]
                                  : true;
    if (!low) {
      x += h * patch_displacement(d, k, u, v);
    } else {
      // The quadratic interpolant of t · d₂ (basis 4 λ_i λ_j of the edge midpoints), then the
      // rest of the patch sheared at the nodes.
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) x += 4 * l[i] * l[j] * q[i][j];
      if (k > 2) x += h * (patch_displacement(d, k, u, v) - quadratic_part(u, v));
    }
    nodes.row(Eigen::Index(n)) = x.transpose();
  }
  return nodes;
}

}  // namespace curvefem::meshing::curved
