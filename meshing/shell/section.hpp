#pragma once
// is_section (thesis §4.4, Definition 4.1): is a triangle mesh M a section of the shell, i.e. does
// every fiber cross M exactly once, transversally? Then P restricted to M is a bijection onto the
// input (and onto any other section), and M is free of self-intersections.
//
// What check() decides (exact predicates wherever a sign is decided; shell_intersection.hpp):
//   (a) manifold    M is closed, edge-manifold and consistently oriented (every edge in exactly
//                   two faces, used once in each direction).
//   (b) inside      every vertex of M lies in a prism (exact point location).
//   (c) separated   no face of M meets a base or top triangle, except a face corner sitting
//                   exactly on a pinch point (singular pillar) touching the cage there alone.
//                   With (b), every face of M lies inside the shell (the shell is closed: its
//                   boundary is base ∪ top). A degenerate (zero-area) face fails (c).
//   (d) transversal for every prism and every face t of M in section contact with one of the
//                   prism's non-degenerate canonical split tets (meets the open tet, or lies in a
//                   facet plane and meets the facet's relative interior), n_t · h > 0 for every
//                   non-singular half-pillar h of that prism: the same condition verify_shell
//                   checks for the input (I2), with the argument in shell_intersection.cpp that
//                   every fiber then meets M only in isolated, transversal crossings, all in the
//                   direction of the pillars.
//   (e) degree      for each edge-connected component of the middle surface, one test fiber (at
//                   a fixed generic (u, v) of one of its prisms; up to 4 are tried until one
//                   misses the edges and vertices of M) crosses M exactly once.
// Why (a)–(e) suffice: by (a)–(d) a crossing can neither appear nor vanish as the fiber moves
// (crossings are transversal and of one sign, M has no boundary, and it stays away from the fiber
// ends), so the number of crossings is constant over each component of the middle surface outside
// the finitely many fibers through vertices of M — a connected set; (e) makes that number 1.
// Like verify_shell, (d) uses the canonical split (shell_geometry.hpp), not all 6 splits, and
// overlapping prisms of a self-intersecting shell are not excluded.
//
// The local tests (c) and (d) take one triangle, so a mesh editor can check only the triangles
// an operation changed: a closed M that starts as a section and is edited by local operations
// that keep (a) and (b) and pass (c) + (d) on every changed triangle stays one (the degree is
// unchanged: fibers away from the edit are untouched). section_remesh.hpp relies on this.

#include <Eigen/Core>
#include <array>
#include <memory>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/projection.hpp"

namespace curvefem::meshing::shell {

struct SectionCheck {
  bool manifold = false;          // (a)
  int vertices_outside = 0;       // (b) vertices of M in no prism
  int faces_crossing_cage = 0;    // (c) faces of M meeting base or top
  int faces_not_transversal = 0;  // (d) faces of M failing the pillar test in a prism they enter
  int degree_failures = 0;  // (e) middle-surface components whose test fiber crosses M ≠ 1 time
  double seconds = 0;
  bool is_section() const {
    return manifold && vertices_outside == 0 && faces_crossing_cage == 0 &&
           faces_not_transversal == 0 && degree_failures == 0;
  }
};

class SectionChecker {
 public:
  using Triangle = std::array<Eigen::Vector3d, 3>;
  // Prepares every prism's split tets, pillars and base/top triangles.
  // The projection (and its shell) must outlive the checker. Queries are const and thread-safe.
  explicit SectionChecker(const ShellProjection& projection);
  ~SectionChecker();
  SectionChecker(const SectionChecker&) = delete;
  SectionChecker& operator=(const SectionChecker&) = delete;

  // The singular (pinch) shell vertex whose middle position is exactly p, or -1.
  int pinch_vertex(const Eigen::Vector3d& p) const;
  // (c) for one triangle; pinch[k] = pinch_vertex(corner k). Each base/top triangle lies in its
  // prism's bounding box, so only the prisms near t are tested.
  bool separated(const Triangle& t, const std::array<int, 3>& pinch) const;
  // (d) for one triangle, over every prism whose bounding box meets it.
  bool transversal(const Triangle& t) const;
  // Both, sharing the search for the prisms near t (what a mesh editor calls per new triangle).
  bool triangle_ok(const Triangle& t, const std::array<int, 3>& pinch) const;
  // (a)–(e) for a whole mesh.
  SectionCheck check(const SurfaceMesh& m) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

// SectionChecker(projection).check(m).
SectionCheck check_section(const ShellProjection& projection, const SurfaceMesh& m);

}  // namespace curvefem::meshing::shell
