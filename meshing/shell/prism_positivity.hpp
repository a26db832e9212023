#pragma once
// Exact positivity of linear prisms (thesis §4.3; reference-notes §4.1).
//
// A prism has base corners 0,1,2 and top corners 3,4,5 (pillar i joins i and i+3). It is valid
// when all 12 non-degenerate tetrahedra on its 6 corners that appear in any of its 3-tet splits
// have positive orientation (exact orient3d); the 12 are grouped in blocks of 4 by the pillar
// they rely on, and the blocks of singular (zero-length) pillars are skipped. A shell face is
// checked as two stacked prisms, base–mid and mid–top: 24 tets. Passing guarantees that every
// one of the 6 possible 3-tet splits of each half is positive.

#include <Eigen/Core>
#include <array>

namespace curvefem::meshing::shell {

// Local corner indices of the 12 tets; block i (entries 4i..4i+3) relies on pillar i.
const std::array<std::array<int, 4>, 12>& prism_tets();

// corners: base 0..2, top 3..4..5. singular[i]: pillar i has zero length (skip its block).
bool prism_positive(const std::array<Eigen::Vector3d, 6>& corners,
                    const std::array<bool, 3>& singular = {});

// Both halves of a shell face: (base, mid) and (mid, top).
bool shell_face_positive(const std::array<Eigen::Vector3d, 3>& base,
                         const std::array<Eigen::Vector3d, 3>& mid,
                         const std::array<Eigen::Vector3d, 3>& top,
                         const std::array<bool, 3>& singular = {});

}  // namespace curvefem::meshing::shell
