#include "meshing/shell/prism_location.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Dense>
#include <algorithm>

#include "meshing/shell/shell_geometry.hpp"

namespace curvefem::meshing::shell {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
K::Point_3 pt(const Eigen::Vector3d& p) { return K::Point_3(p.x(), p.y(), p.z()); }
constexpr double k_xy[3][2] = {{0, 0}, {1, 0}, {0, 1}};
}  // namespace

std::optional<PrismCoordinates> locate_in_prism(const Eigen::Vector3i& F,
                                                const std::array<Eigen::Vector3d, 3>& base,
                                                const std::array<Eigen::Vector3d, 3>& mid,
                                                const std::array<Eigen::Vector3d, 3>& top,
                                                const Eigen::Vector3d& p) {
  return PrismLocator(F, base, mid, top).locate(p);
}

PrismLocator::PrismLocator(const Eigen::Vector3i& F, const std::array<Eigen::Vector3d, 3>& base,
                           const std::array<Eigen::Vector3d, 3>& mid,
                           const std::array<Eigen::Vector3d, 3>& top) {
  for (int a = 0; a < 3; ++a) {
    double lo = base[0][a], hi = lo;
    for (const auto* layer : {&base, &mid, &top})
      for (const Eigen::Vector3d& c : *layer) {
        lo = std::min(lo, c[a]);
        hi = std::max(hi, c[a]);
      }
    m_lo[a] = lo;
    m_hi[a] = hi;
  }
  const int r = min_rotation(F);
  const bool type_a = is_type_a(F);
  int n = 0;
  for (int half = 0; half < 2; ++half)
    for (const auto& tet : split_tets(type_a)) {
      Tet& t = m_tets[std::size_t(n++)];
      t.half = half;
      K::Point_3 c[4];
      for (int k = 0; k < 4; ++k) {
        const int local = (r + tet[k] % 3) % 3;
        t.corner[std::size_t(k)] = tet[k];
        t.e[std::size_t(k)] = tet[k] < 3 ? (half == 0 ? base[local] : mid[local])
                                         : (half == 0 ? mid[local] : top[local]);
        c[k] = pt(t.e[std::size_t(k)]);
      }
      t.orientation = int(CGAL::orientation(c[0], c[1], c[2], c[3]));
    }
}

std::optional<PrismCoordinates> PrismLocator::locate(const Eigen::Vector3d& p) const {
  // Outside the box of the nine points, p is in no closed split tet (each lies in its corners'
  // box); compared exactly, so the answer is the one the orientation tests below would give.
  for (int a = 0; a < 3; ++a)
    if (p[a] < m_lo[a] || p[a] > m_hi[a]) return std::nullopt;
  const K::Point_3 q = pt(p);
  for (const Tet& t : m_tets) {
    const int o = t.orientation;
    if (o == 0) continue;  // pinched
    // Facet i (opposite corner i) and the side corner i lies on: orientation(facet, c[i]) is
    // o times the sign of the permutation (facet, i) of (0, 1, 2, 3) (the predicate is exactly
    // antisymmetric).
    static const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    static const int parity[4] = {-1, 1, -1, 1};
    bool inside = true;
    for (int i = 0; i < 4 && inside; ++i) {
      const auto& fc = faces[i];
      const auto side = CGAL::orientation(pt(t.e[std::size_t(fc[0])]), pt(t.e[std::size_t(fc[1])]),
                                          pt(t.e[std::size_t(fc[2])]), q);
      inside = side == CGAL::COPLANAR || int(side) == parity[i] * o;
    }
    if (!inside) continue;
    const auto& e = t.e;
    Eigen::Matrix3d A;
    A << e[1] - e[0], e[2] - e[0], e[3] - e[0];
    const Eigen::Vector3d l = A.colPivHouseholderQr().solve(p - e[0]);
    const double w[4] = {1 - l.sum(), l[0], l[1], l[2]};
    PrismCoordinates out;
    for (int k = 0; k < 4; ++k) {
      const int corner = t.corner[std::size_t(k)];
      out.u += w[k] * k_xy[corner % 3][0];
      out.v += w[k] * k_xy[corner % 3][1];
      out.h += w[k] * ((corner < 3 ? -1.0 : 0.0) + t.half);
    }
    return out;
  }
  return std::nullopt;
}

}  // namespace curvefem::meshing::shell
