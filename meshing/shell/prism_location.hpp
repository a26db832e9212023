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

}  // namespace curvefem::meshing::shell
