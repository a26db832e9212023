// Exact geometric tests of meshing/check: degenerate faces and self-intersecting face pairs.
//
// The only place of curvefem that includes CGAL (self_intersections.cpp, CGAL linked PRIVATE).
// All predicates are exact (CGAL::Exact_predicates_inexact_constructions_kernel, EPICK) on the
// double coordinates of V (#V × 3); F is #F × 3 with valid 0-based ids.
//
// Intersection rule (the one of CGAL::Polygon_mesh_processing::self_intersections), for two
// non-degenerate faces f ≠ g, "shared" meaning the same vertex *index* (coincident but unwelded
// vertices are not shared):
//   - no shared vertex: the closed triangles intersect;
//   - one shared vertex v: the edge of f opposite v meets triangle g, or vice versa;
//   - two shared vertices (an edge): the faces are coplanar and fold onto each other (their third
//     corners lie on the same side of the shared edge);
//   - three shared vertices (duplicate faces): always intersecting.
// Degenerate faces (exactly collinear corners, including repeated indices) are never paired: they
// are reported as degenerate instead (as PMP does).
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

namespace curvefem::check {

/// #F flags: 1 when the face repeats a vertex index or its three corners are exactly collinear.
std::vector<char> exactly_degenerate_faces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);

enum class SelfIntersectionEngine {
  automatic,  ///< PMP on a CGAL::Surface_mesh when `is_oriented_manifold`, otherwise `soup`
  mesh,       ///< CGAL::Polygon_mesh_processing::self_intersections (requires an oriented manifold)
  soup,       ///< CGAL::box_self_intersection_d + the rule above on the indexed triangle soup
};

struct SelfIntersectionResult {
  std::vector<std::pair<int, int>> pairs;  ///< (f, g) with f < g, sorted
  bool used_mesh_api = false;              ///< true when PMP's mesh function produced `pairs`
};

/// Self-intersecting pairs of non-degenerate faces (`degenerate` as from
/// exactly_degenerate_faces). `is_oriented_manifold`: the caller has verified that every edge has
/// at most two faces traversing it in opposite directions, no vertex is a pinch and no face repeats
/// an index (the soup is then a valid CGAL halfedge mesh). Parallel with oneTBB when available.
/// Throws curvefem::Error if `engine == mesh` and the soup cannot be built into a Surface_mesh.
SelfIntersectionResult find_self_intersections(
    const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::vector<char>& degenerate,
    bool is_oriented_manifold, SelfIntersectionEngine engine = SelfIntersectionEngine::automatic);

/// The number of self-intersecting pairs of non-degenerate faces of an oriented manifold (V, F)
/// (PMP's mesh engine; degenerate faces are not paired).
int count_self_intersecting_pairs(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);

/// Exactly intersecting face pairs between two surfaces (a's faces against b's; the two share no
/// vertex, so touching counts): the union's soup pairs with one face from each.
int intersecting_pairs_between(const Eigen::MatrixXd& Va, const Eigen::MatrixXi& Fa,
                               const Eigen::MatrixXd& Vb, const Eigen::MatrixXi& Fb);

}  // namespace curvefem::check
