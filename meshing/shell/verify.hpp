#pragma once
// Independent verification of a shell (reference-notes §4.7): code paths separate from the
// construction check every claim the shell makes and report counts.
//   positive      every half-prism passes the exact 12-tet test (24 per face)
//   separated     no input triangle intersects a base or top triangle (queried from the input
//                 side against an index of the base/top triangles; contact at pinch points only)
//   section       for every prism, every input triangle in section contact with its canonical
//                 split tets (meets an open tet, or lies in a tet facet and meets its relative
//                 interior; shell_intersection.hpp) has a
//                 normal making a positive dot product with every non-singular pillar, so every
//                 fiber crosses the input transversally and at most once (thesis §4.4, I2)
//   reference     with feature chains (Shell::reference): the faces of the reference copy with a
//                 snapped corner meet no other face of it beyond common corners and edges, and
//                 none is flattened below k_min_reference_area_ratio of its input face's area;
//                 the checks above use the copy, exactly
//   distortion    the smallest cosine between a non-singular half-pillar and the normal of an
//                 input face in section contact with its prism (thesis §4.4's projection
//                 distortion; reported, not part of valid(): simplification bounds it by
//                 SimplifyOptions::section_cos, prisms it never touched keep their own)
//   roundtrip     every input vertex x: P⁻¹ then P returns x; max |x' - x| / bbox edge (pinch
//                 points, zero-length fibers, included); a vertex mapped back farther than
//                 k_roundtrip_miss_rel counts as a failure
// A locally injective shell (Shell::local_sheets) is checked for what it claims: separation and
// section per prism against its local sheet (local_sheets.hpp, reached from face_parent), P⁻¹ of
// a vertex through a face at it.

#include <vector>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::meshing::shell {

/// A roundtrip P(P⁻¹(x)) farther than this from x (relative to the longest bbox edge) is a
/// failure, not rounding.
inline constexpr double k_roundtrip_miss_rel = 1e-6;

struct ShellVerification {
  int faces = 0;
  int non_positive_faces = 0;
  int intersecting_input_faces = 0;
  int non_section_faces = 0;
  // Faces of the reference copy (Shell::reference) meeting another face beyond their common
  // corners and edge (the section argument needs the copy embedded, as the input is).
  int reference_self_intersections = 0;
  // Faces of the reference copy flattened below k_min_reference_area_ratio of their input face's
  // area (the copy-to-input correspondence is then not one-to-one up to rounding).
  int reference_collapsed_faces = 0;
  // Input vertices P⁻¹ or P could not map, or mapped back farther than k_roundtrip_miss_rel.
  int roundtrip_failures = 0;
  double roundtrip_max_error_rel = 0;
  // Smallest half-pillar/normal cosine over section-contact pairs (1: no pair; -1 with a
  // non-section prism).
  double min_pillar_cos = 1;
  double seconds = 0;
  bool positive() const { return non_positive_faces == 0; }
  bool separated() const { return intersecting_input_faces == 0; }
  bool section() const { return non_section_faces == 0; }
  bool embedded_reference() const { return reference_self_intersections == 0; }
  bool valid() const {
    return positive() && separated() && section() && embedded_reference() &&
           reference_collapsed_faces == 0 && roundtrip_failures == 0;
  }
};

ShellVerification verify_shell(const Shell& shell, const SurfaceMesh& input);

// The prisms failing the section condition above, in increasing order (verify_shell counts
// them; build_beveled_shell bevels under them). Parallel over prisms; the result does not depend
// on the thread count.
std::vector<int> non_section_prisms(const Shell& shell, const SurfaceMesh& input);

}  // namespace curvefem::meshing::shell
