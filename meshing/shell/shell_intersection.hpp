#pragma once
// Exact queries against the input surface used by shell construction and verification (CGAL
// AABB tree and filtered exact predicates behind a pimpl).

#include <Eigen/Core>
#include <array>
#include <limits>
#include <memory>
#include <vector>

namespace curvefem::meshing::shell {

// ---- Exact predicates for the section condition (I2) -------------------------------------------
// All decide from the double coordinates exactly (interval filter, exact fallback); no
// constructed point or plane decides anything. shell_intersection.cpp explains why the section
// condition needs these, and not the closed "touching" test.

// Sign (+1, 0, −1) of ((b − a) × (c − a)) · (to − from) for tri = (a, b, c).
int normal_dot_sign(const std::array<Eigen::Vector3d, 3>& tri, const Eigen::Vector3d& from,
                    const Eigen::Vector3d& to);

// Does the closed triangle meet the open interior of the tetrahedron? The tetrahedron must be
// non-degenerate (nonzero orient3d; either orientation). Separating-axis test with weak
// inequalities over the 4 facet planes, the triangle's plane and the 18 edge–edge planes.
bool triangle_meets_open_tet(const std::array<Eigen::Vector3d, 3>& tri,
                             const std::array<Eigen::Vector3d, 4>& tet);

// Does the closed triangle lie in the plane of the non-degenerate triangle `facet` and meet its
// relative interior? (False when not coplanar.)
bool triangle_meets_open_facet(const std::array<Eigen::Vector3d, 3>& tri,
                               const std::array<Eigen::Vector3d, 3>& facet);

// Section contact of a triangle with one non-degenerate split tet of a prism: the triangle
// meets the open tet, or lies in the plane of one of its 4 facets and meets that facet's
// relative interior. Contact only along edges or at vertices of the tet, or a transversal touch
// of a facet at its boundary, is not section contact.
bool triangle_section_contact(const std::array<Eigen::Vector3d, 3>& tri,
                              const std::array<Eigen::Vector3d, 4>& tet);

// Do the closed triangles a and b meet anywhere but at a pinch point, their common corner
// a[ka] == b[kb] (ka = kb = -1: no such corner, any contact counts)? Contact at that point alone is
// decided exactly with the opposite edges; coplanar triangles sharing it count as meeting
// (conservative). Both triangles must be non-degenerate.
bool triangles_meet_beyond_pinch(const std::array<Eigen::Vector3d, 3>& a, int ka,
                                 const std::array<Eigen::Vector3d, 3>& b, int kb);

// Does the closed segment [p, q] cross the plane of the wedge W = {apex + α(a − apex) +
// β(b − apex) : α, β ≥ 0} at a point of W? The wedge must be non-degenerate (apex, a, b not
// collinear; false otherwise); a segment lying in its plane does not cross it. Exact: the segment's
// end points on either side of the plane (or on it), and the crossing point on the inner side of
// the lines apex–a and apex–b, all as signs of orient3d.
bool segment_crosses_wedge(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                           const Eigen::Vector3d& apex, const Eigen::Vector3d& a,
                           const Eigen::Vector3d& b);

// A vertex of the reference copy of the input (feature chains, thesis §5.3) moved onto the
// straight coarse feature edge between input vertices a and b: it stands for the point
// V[a] + s (V[b] − V[a]) itself, which is decided on exactly, not for its rounding to doubles.
// An end that is no vertex of the surface indexed (a = -1 or b = -1: the shell was coarsened on a
// refinement of the input whose vertex it is, restore_input_ids) is given by its position.
/// A reference face whose area fell below this fraction of its input face's is collapsed
/// (InputSurfaceIndex::face_area_ratio).
inline constexpr double k_min_reference_area_ratio = 1e-6;

struct SnappedVertex {
  int vertex = -1, a = -1, b = -1;
  double s = 0;  // in (0, 1)
  // When a, b < 0 (NaN otherwise: an end of -1 without its position is refused).
  Eigen::Vector3d pa = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()),
                  pb = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
};

// Exact closed-set tests with corners of the reference copy given as snapped points (above) or
// plain doubles; the closed triangle–tet test and the triangle–triangle test by separating axes
// over orientation signs. Exposed for tests.
struct ExactPoint {
  Eigen::Vector3d p{0, 0, 0};  // the point, or its rounding when snapped
  bool snapped = false;
  Eigen::Vector3d a{0, 0, 0}, b{0, 0, 0};
  double s = 0;
  ExactPoint() = default;
  ExactPoint(const Eigen::Vector3d& q) : p(q) {}  // NOLINT: a plain point converts implicitly
  static ExactPoint on_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double s);
};
// Does the closed (non-degenerate) triangle meet the closed non-degenerate tetrahedron?
bool exact_triangle_meets_tet(const std::array<ExactPoint, 3>& tri,
                              const std::array<Eigen::Vector3d, 4>& tet);
// Do the closed triangles meet? Coplanar triangles, and a degenerate (collinear) first triangle,
// count as meeting (conservative; the shell never keeps a degenerate reference face).
bool exact_triangles_meet(const std::array<ExactPoint, 3>& a,
                          const std::array<Eigen::Vector3d, 3>& b);
// triangle_section_contact and normal_dot_sign with exact corners.
bool exact_section_contact(const std::array<ExactPoint, 3>& tri,
                           const std::array<Eigen::Vector3d, 4>& tet);
int exact_normal_dot_sign(const std::array<ExactPoint, 3>& tri, const Eigen::Vector3d& from,
                          const Eigen::Vector3d& to);
// Are the three points collinear (exact)?
bool exact_collinear(const std::array<ExactPoint, 3>& tri);

class InputSurfaceIndex {
 public:
  InputSurfaceIndex(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
  // The same over the reference copy with these vertices snapped.
  InputSurfaceIndex(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                    const std::vector<SnappedVertex>& snaps);
  ~InputSurfaceIndex();
  InputSurfaceIndex(const InputSurfaceIndex&) = delete;
  InputSurfaceIndex& operator=(const InputSurfaceIndex&) = delete;

  // Distance from `origin` along `direction` (any length; the distance is Euclidean) to the
  // first input face not in `ignore` (+infinity when the ray leaves without hitting).
  // `among` (sorted; null: every face): only these faces count (local_sheets.hpp), here and in
  // triangle_intersects, faces_containing and segment_hit.
  double ray_distance(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                      const std::vector<int>& ignore,
                      const std::vector<int>* among = nullptr) const;

  // Does the triangle intersect the input? Triangle corner k with singular[k] lies on the input
  // at input vertex `corner_ids[k]` (a pinch point): contact at that point alone is allowed
  // (tested exactly with the opposite edges, no constructed points).
  bool triangle_intersects(const std::array<Eigen::Vector3d, 3>& triangle,
                           const std::array<bool, 3>& singular, const Eigen::Vector3i& corner_ids,
                           const std::vector<int>* among = nullptr) const;

  // triangle_intersects restricted to input face f: does the triangle meet it (with the same
  // pinch rule)?
  bool triangle_meets_face(const std::array<Eigen::Vector3d, 3>& triangle,
                           const std::array<bool, 3>& singular, const Eigen::Vector3i& corner_ids,
                           int f) const;

  // Input faces whose triangle intersects the (closed) tetrahedron (exact), in increasing order.
  std::vector<int> faces_touching_tet(const std::array<Eigen::Vector3d, 4>& tet) const;
  // Input faces intersecting at least one of the closed tetrahedra (exact), in increasing order
  // (one tree traversal for all of them). `known` (sorted, unique): faces the caller knows to
  // touch one of them (e.g. a corner of the face located in a tet by exact predicates); they are
  // reported without a test, except moved faces of the reference copy, which are tested anyway.
  std::vector<int> faces_touching_tets(const std::vector<std::array<Eigen::Vector3d, 4>>& tets,
                                       const std::vector<int>& known = {}) const;

  // Non-degenerate input faces whose closed triangle contains p (exact), in increasing order.
  std::vector<int> faces_containing(const Eigen::Vector3d& p,
                                    const std::vector<int>* among = nullptr) const;
  // Input faces whose bounding box overlaps [lo, hi] (a superset of the faces meeting the box;
  // moved faces of the reference copy are found where they are now, and where they were).
  std::vector<int> faces_in_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  // Does input face f intersect the closed tetrahedron (exact)?
  bool face_touches_tet(int f, const std::array<Eigen::Vector3d, 4>& tet) const;
  // triangle_section_contact of input face f with a non-degenerate tet (exact).
  bool face_section_contact(int f, const std::array<Eigen::Vector3d, 4>& tet) const;
  // Input face f as a triangle (of the reference copy, rounded where snapped).
  std::array<Eigen::Vector3d, 3> face_triangle(int f) const;
  // Exact sign of n_f · (to − from), n_f the normal of face f of the reference copy.
  int face_normal_dot_sign(int f, const Eigen::Vector3d& from, const Eigen::Vector3d& to) const;
  // Is face f of the reference copy degenerate (collinear corners, exact)?
  bool face_degenerate(int f) const;
  // Area of face f of the reference copy (rounded where snapped) over the input face's (1 when
  // the input face has no area). Below k_min_reference_area_ratio the copy has flattened the face
  // (snapped corners and a rounded one collinear up to rounding: not exactly degenerate, yet P,
  // which reads a crossing of the copy as the input point with the same barycentric coordinates,
  // sends points of a segment anywhere across the input face).
  double face_area_ratio(int f) const;
  // Does face f of the reference copy meet another face of it anywhere but at their common
  // corners and edge (exact; coplanar faces sharing a corner, or overlapping, count as meeting)?
  // Snapping can fold the reference copy over itself, and the section argument needs it embedded.
  bool face_self_intersects(int f) const;

  // ---- The reference copy ----------------------------------------------------------------------
  // Snapped vertices change what triangle_intersects, faces_touching_tet(s), face_touches_tet,
  // face_section_contact, face_triangle, face_normal_dot_sign and faces_in_box see; faces with a
  // snapped corner ("moved") are tested exactly against the snapped points. faces_containing and
  // segment_hit see the moved faces as their rounded triangles; ray_distance and closest_face
  // see the unmoved input. V() stays the input's. Snapping is
  // not thread-safe: no query may run meanwhile.
  void snap_vertex(const SnappedVertex& snap);
  void unsnap_vertex(int x);  // back to its input position
  // The snap of x, if snapped.
  const SnappedVertex* snap_of(int x) const;
  std::vector<SnappedVertex> snaps() const;  // in increasing vertex order
  // Vertex positions of the reference copy (rounded where snapped; V() while nothing is).
  const Eigen::MatrixXd& reference_V() const;
  // The faces with a snapped corner, and face f with its exact corners.
  const std::vector<int>& moved_faces() const;
  std::array<ExactPoint, 3> exact_face(int f) const;

  // Closest input point: face id and the point.
  int closest_face(const Eigen::Vector3d& p, Eigen::Vector3d& closest) const;

  // First input face hit by segment [a, b] (exact do_intersect for the candidates, closest to a
  // by a barycentric solve); -1 if none. bary receives the barycentric coordinates of the hit in
  // that face.
  int segment_hit(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Eigen::Vector3d& bary,
                  const std::vector<int>* among = nullptr) const;

  const Eigen::MatrixXd& V() const;
  const Eigen::MatrixXi& F() const;

 private:
  // Triangle c against input face f (triangle_intersects' rule): a moved face exactly, a pinch at
  // one of its corners refused; another face, if it meets c (`known_to_meet`: the caller's tree
  // query said so), beyond the pinch allowed at a singular corner of c.
  bool face_contact(const std::array<Eigen::Vector3d, 3>& c, const std::array<bool, 3>& singular,
                    const Eigen::Vector3i& corner_ids, int f, bool known_to_meet) const;
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace curvefem::meshing::shell
