#pragma once
// What a tet mesh's boundary allows its elements (issue 21's quality goal, diagnostic only).
//
// Every boundary triangle belongs to one tet, and every boundary edge to the tets in its wedge,
// so the boundary alone bounds their quality. For a STRAIGHT tet (bounds, not estimates; for a
// curved one they describe the straight tet on the same corners):
//   MIPS floor    the curved MIPS of jacobian_certificate.hpp (‖J‖²_F ‖J⁻¹‖²_F against the
//                 right reference tet) of any tet with face (a, b, c) is at least
//                 (ℓ / 2h)², ℓ its longest edge and h = 2·area / ℓ its smallest height:
//                 J maps the reference face (edges ≤ √2, area ≥ 1/2) onto it, so σ_max ≥ ℓ/√2
//                 and σ_min ≤ √2 h, and ‖J‖²_F ‖J⁻¹‖²_F ≥ (σ_max / σ_min)².
//   SJ ceiling    the scaled Jacobian (√2 det over the product of a corner's edges, 1 for the
//                 regular tet) at the corner of a face's smallest angle θ is at most √2 sin θ;
//                 at a corner on a boundary edge whose interior dihedral angle α is below 90°
//                 it is at most √2 sin α (the tet's own dihedral there is at most α).
// A boundary face with a MIPS floor above 1e4, or an SJ ceiling below 1e-3, makes issue 21's
// goal (max MIPS ≤ 1e4, min SJ ≥ 1e-3) unreachable for straight tets whatever the volume stages
// do: the miss is the coarse boundary's (the coarsening, the features it keeps).

#include <Eigen/Core>
#include <array>
#include <vector>

namespace curvefem::meshing::curved {

/// (ℓ / 2h)² of triangle (a, b, c): +∞ when it has no area.
double triangle_mips_floor(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c);
/// √2 sin θ of its smallest angle θ (0 when it has no area).
double triangle_sj_ceiling(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c);

struct BoundaryLimits {
  int faces = 0, edges = 0;
  double mips_floor = 0;  // the largest face floor
  int mips_floor_face = -1;
  int faces_mips_floor_above_1e4 = 0;
  double sj_ceiling = 1.4142135623730951;  // the smallest ceiling, faces and edges
  int sj_ceiling_face = -1;                // the face giving it, or -1 (an edge)
  int faces_sj_ceiling_below_1e2 = 0, faces_sj_ceiling_below_1e3 = 0;
  double min_dihedral_deg = 360;  // smallest interior dihedral angle over the boundary edges
  int edges_sj_ceiling_below_1e2 = 0, edges_sj_ceiling_below_1e3 = 0;
  Eigen::Vector3d mips_floor_at = Eigen::Vector3d::Zero();  // centroid of mips_floor_face
};

/// `faces`: the boundary triangles as node ids into X (#nodes × 3), oriented outward (the
/// volume on the side opposite their normal). Edges used by other than two faces are skipped
/// by the dihedral part.
BoundaryLimits boundary_limits(const Eigen::MatrixXd& X,
                               const std::vector<std::array<int, 3>>& faces);

}  // namespace curvefem::meshing::curved
