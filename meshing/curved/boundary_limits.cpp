#include "meshing/curved/boundary_limits.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

namespace curvefem::meshing::curved {

double triangle_mips_floor(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c) {
  const double area2 = (b - a).cross(c - a).norm();  // twice the area
  const double longest2 =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  if (!(area2 > 0)) return std::numeric_limits<double>::infinity();
  // h = area2 / ℓ, so ℓ / 2h = ℓ² / (2 area2).
  const double ratio = longest2 / (2 * area2);
  return ratio * ratio;
}

double triangle_sj_ceiling(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c) {
  const double area2 = (b - a).cross(c - a).norm();
  std::array<double, 3> len{(b - a).norm(), (c - b).norm(), (a - c).norm()};
  std::sort(len.begin(), len.end());
  // The smallest angle is opposite the shortest edge, between the two longer ones.
  if (!(area2 > 0) || !(len[1] * len[2] > 0)) return 0;
  return std::numbers::sqrt2 * std::min(1.0, area2 / (len[1] * len[2]));
}

BoundaryLimits boundary_limits(const Eigen::MatrixXd& X,
                               const std::vector<std::array<int, 3>>& faces) {
  BoundaryLimits r;
  r.faces = int(faces.size());
  auto at = [&](int v) { return Eigen::Vector3d(X.row(v).transpose()); };
  // Directed edge (a, b) → (face, opposite corner).
  std::map<std::pair<int, int>, std::pair<int, int>> directed;
  for (int f = 0; f < r.faces; ++f) {
    const auto& t = faces[std::size_t(f)];
    const Eigen::Vector3d a = at(t[0]), b = at(t[1]), c = at(t[2]);
    const double floor = triangle_mips_floor(a, b, c);
    if (floor > r.mips_floor || r.mips_floor_face < 0) {
      r.mips_floor = floor;
      r.mips_floor_face = f;
      r.mips_floor_at = (a + b + c) / 3;
    }
    r.faces_mips_floor_above_1e4 += floor > 1e4;
    const double ceiling = triangle_sj_ceiling(a, b, c);
    if (ceiling < r.sj_ceiling) {
      r.sj_ceiling = ceiling;
      r.sj_ceiling_face = f;
    }
    r.faces_sj_ceiling_below_1e2 += ceiling < 1e-2;
    r.faces_sj_ceiling_below_1e3 += ceiling < 1e-3;
    for (int k = 0; k < 3; ++k) directed[{t[k], t[(k + 1) % 3]}] = {f, t[(k + 2) % 3]};
  }
  for (const auto& [ab, fc] : directed) {
    const auto [a, b] = ab;
    if (a > b) continue;  // each undirected edge once, from its (a < b) direction
    const auto other = directed.find({b, a});
    if (other == directed.end()) continue;
    ++r.edges;
    const Eigen::Vector3d pa = at(a), pb = at(b), c = at(fc.second), d = at(other->second.second);
    const Eigen::Vector3d e = (pb - pa).normalized();
    Eigen::Vector3d u1 = (c - pa) - (c - pa).dot(e) * e, u2 = (d - pa) - (d - pa).dot(e) * e;
    if (!(u1.norm() > 0) || !(u2.norm() > 0)) continue;
    u1.normalize();
    u2.normalize();
    // Face (a, b, c) has outward normal (b - a) × (c - a); the volume is on the other side. The
    // edge is convex where the other face's inner direction u2 points into the volume there.
    const Eigen::Vector3d n1 = (pb - pa).cross(c - pa);
    const double between = std::atan2(u1.cross(u2).norm(), u1.dot(u2));  // accurate near 0
    const double interior = n1.dot(u2) <= 0 ? between : 2 * std::numbers::pi - between;
    r.min_dihedral_deg = std::min(r.min_dihedral_deg, interior * 180 / std::numbers::pi);
    if (interior >= std::numbers::pi / 2) continue;
    const double ceiling = std::numbers::sqrt2 * std::sin(interior);
    if (ceiling < r.sj_ceiling) {
      r.sj_ceiling = ceiling;
      r.sj_ceiling_face = -1;
    }
    r.edges_sj_ceiling_below_1e2 += ceiling < 1e-2;
    r.edges_sj_ceiling_below_1e3 += ceiling < 1e-3;
  }
  return r;
}

}  // namespace curvefem::meshing::curved
