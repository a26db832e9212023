#include "mapping/input_selection.hpp"

#include <cmath>
#include <vector>

namespace curvefem::mapping {

std::function<bool(const Eigen::Vector3d&)> input_selection_filter(
    const Selection& s, const SurfaceMesh& input, std::shared_ptr<const BoundaryInverse> inverse,
    bool closed) {
  if (s.kind == Selection::Kind::all) return {};
  if (!closed || !uses_face_data(s))
    return [s, &input, inverse](const Eigen::Vector3d& x) {
      return selects(s, site_of(input, inverse->at(x)));
    };
  auto vf = std::make_shared<std::vector<std::vector<int>>>(input.num_vertices());
  for (int f = 0; f < input.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) (*vf)[std::size_t(input.F(f, k))].push_back(f);
  return [s, &input, inverse, vf](const Eigen::Vector3d& x) {
    const InputPoint p = inverse->at(x);
    if (selects(s, site_of(input, p))) return true;
    constexpr double tol = 1e-9;
    std::vector<int> others;
    for (int k = 0; k < 3; ++k) {
      const int a = input.F(p.face, k);
      if (p.bary[k] >= 1 - tol) others = (*vf)[std::size_t(a)];  // at that vertex
      if (std::abs(p.bary[k]) <= tol) {                          // on the edge opposite corner k
        const int b = input.F(p.face, (k + 1) % 3), c = input.F(p.face, (k + 2) % 3);
        for (int g : (*vf)[std::size_t(b)])
          for (int j = 0; j < 3; ++j)
            if (input.F(g, j) == c) others.push_back(g);
      }
    }
    for (int g : others) {
      if (g == p.face) continue;
      InputPoint q = p;
      q.face = g;
      if (selects(s, site_of(input, q))) return true;
    }
    return false;
  };
}

}  // namespace curvefem::mapping
