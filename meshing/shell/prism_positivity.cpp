// Exact positivity of linear prisms (see the header).
//
// Orientation convention: tet (a, b, c, d) is positive when (b − a) × (c − a) · (d − a) > 0.
// CGAL::orientation(p, q, r, s) is the sign of det[q − p, r − p, s − p] (orientationC3), the same
// triple product, so POSITIVE ⟺ positive here; the Epick kernel evaluates it exactly (filtered).
// Every tuple below is positive on the right prism with base (0,0,0), (1,0,0), (0,1,0) and top =
// base + (0,0,1) (tests/meshing/shell/test_shell_predicates.cpp checks this and that the 12 are
// exactly the tets of the 6 valid 3-tet splits).

#include "meshing/shell/prism_positivity.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace curvefem::meshing::shell {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

Point point(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }

}  // namespace

const std::array<std::array<int, 4>, 12>& prism_tets() {
  static const std::array<std::array<int, 4>, 12> tets = {{
      // pillar 0–3
      {0, 2, 3, 4},
      {0, 3, 4, 5},
      {0, 1, 5, 3},
      {0, 1, 2, 3},
      // pillar 1–4
      {1, 2, 3, 4},
      {0, 1, 2, 4},
      {0, 1, 5, 4},
      {1, 3, 4, 5},
      // pillar 2–5
      {1, 2, 3, 5},
      {0, 2, 5, 4},
      {0, 1, 2, 5},
      {2, 3, 4, 5},
  }};
  return tets;
}

bool prism_positive(const std::array<Eigen::Vector3d, 6>& corners,
                    const std::array<bool, 3>& singular) {
  std::array<Point, 6> p;
  for (int i = 0; i < 6; ++i) p[i] = point(corners[i]);
  const auto& tets = prism_tets();
  for (int block = 0; block < 3; ++block) {
    if (singular[block]) continue;
    for (int k = 4 * block; k < 4 * block + 4; ++k) {
      const auto& t = tets[k];
      if (CGAL::orientation(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) != CGAL::POSITIVE) return false;
    }
  }
  return true;
}

bool shell_face_positive(const std::array<Eigen::Vector3d, 3>& base,
                         const std::array<Eigen::Vector3d, 3>& mid,
                         const std::array<Eigen::Vector3d, 3>& top,
                         const std::array<bool, 3>& singular) {
  return prism_positive({base[0], base[1], base[2], mid[0], mid[1], mid[2]}, singular) &&
         prism_positive({mid[0], mid[1], mid[2], top[0], top[1], top[2]}, singular);
}

}  // namespace curvefem::meshing::shell
