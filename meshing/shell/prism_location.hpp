#pragma once
// Point location in one shell prism (reference-notes §3.5): exact orientation predicates decide
// which tet of the canonical split contains a point; only then are barycentric coordinates
// solved in floating point and pushed to prism coordinates.

#include <Eigen/Core>
#include <array>
#include <optional>

namespace curvefem::meshing::shell {

struct PrismCoordinates {
  double u = 0, v = 0, h = 0;  // (u, v) in the face rotated to its smallest id; h in [-1, 1]
};

// Corners in the face's own vertex order (F[0], F[1], F[2]); F gives the global ids that fix
// the rotation and the split type. Points on the boundary count as inside. Pinched tets (zero
// volume, at singular pillars) are skipped.
std::optional<PrismCoordinates> locate_in_prism(const Eigen::Vector3i& F,
                                                const std::array<Eigen::Vector3d, 3>& base,
                                                const std::array<Eigen::Vector3d, 3>& mid,
                                                const std::array<Eigen::Vector3d, 3>& top,
                                                const Eigen::Vector3d& p);

// locate_in_prism for many points in one prism: the prism's box, its split tets and their
// orientations are computed once (locate_in_prism is this class on one point, so both give the
// same answers).
class PrismLocator {
 public:
  PrismLocator(const Eigen::Vector3i& F, const std::array<Eigen::Vector3d, 3>& base,
               const std::array<Eigen::Vector3d, 3>& mid,
               const std::array<Eigen::Vector3d, 3>& top);
  std::optional<PrismCoordinates> locate(const Eigen::Vector3d& p) const;

 private:
  struct Tet {
    std::array<Eigen::Vector3d, 4> e;  // corners
    std::array<int, 4> corner;         // in the split's numbering (0-2 bottom, 3-5 top)
    int half = 0;                      // 0: base to middle, 1: middle to top
    int orientation = 0;               // CGAL's sign of the corners' orientation; 0: pinched
  };
  Eigen::Vector3d m_lo, m_hi;  // the nine corners' box
  std::array<Tet, 6> m_tets;
};

}  // namespace curvefem::meshing::shell
