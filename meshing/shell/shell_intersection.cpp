#include "meshing/shell/shell_intersection.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Interval_nt.h>
#include <CGAL/Mpzf.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace curvefem::meshing::shell {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Triangle = K::Triangle_3;
using Segment = K::Segment_3;
using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

Point pt(const Eigen::Vector3d& p) { return Point(p.x(), p.y(), p.z()); }

// ---- Section contact (I2) -----------------------------------------------------------------
//
// Why "meets an open split tet, or lies in a facet plane meeting the facet's relative interior"
// (triangle_section_contact) is the right set of input faces for the section condition, where
// the closed "touches a split tet" test was too strict.
//
// Setting. A prism P is split canonically into 6 tets (3 per half); those of non-singular
// pillars are positive (I1), those of a singular pillar are flat and coincide with a facet of a
// neighbouring tet (their two rising facets are the same triangle), so the non-degenerate tets
// alone cover P. Inside a tet the fibers are straight and parallel to its pillar (the affine map
// to the reference prism sends the pillar to e_z), so a fiber is a polyline whose directions are
// half-pillars of P. A 3-tet split of a triangular prism has no interior edge: every edge is on
// the prism boundary, and side quads are split the same way from both sides (shell_geometry.hpp),
// so a fiber on a side quad or a pillar is the same polyline in every prism containing it. The
// input is closed, embedded and oriented as the boundary of a solid, so its generalized winding
// number w is 0 or 1 off the surface; by I3 the fibers' end points (on base/top) are off the
// input except the zero-length fibers at pinch points, which are a single input vertex.
// Section condition S(P): every input face t in C(P) = {t : triangle_section_contact(t, T) for
// some non-degenerate split tet T of P} has n_t · h > 0 for every non-singular half-pillar h of P.
//
// Claim: if every prism satisfies I1, I3 and S, every fiber of every prism meets the input in at
// most one point, where it crosses from inside to outside (w: 1 -> 0).
//
// (1) Local coverage. Let x be a non-pinch point where a fiber of P meets the input. x is not on
//     base/top (I3), so a small ball B around x is covered by the closed non-degenerate tets of P
//     and, if x is on P's lateral boundary, of the prisms sharing that side quad or pillar; all
//     fiber directions at x are pillars common to these prisms. Let t be an input face with
//     x ∈ t. Either t meets one of these open tets, or t ∩ B (a 2-D set) lies in the finite union
//     of their facets; then one facet F contains a relatively open piece of t, so t lies in
//     plane(F) and meets relint(F). In both cases t ∈ C(Q) for a prism Q containing x, so
//     n_t · d > 0 for the fiber directions d just below (d_lo) and above (d_hi) x.
// (2) Isolated, signed crossing. Every face at x has a plane with n_t · d ≠ 0 for d = d_lo, d_hi,
//     so the fiber meets the input near x only at x. The open cone
//     K = {y : n_t · (y − x) > 0 for all t ∋ x} avoids the input near x and contains x + εd_lo and
//     x + εd_hi, so w agrees there. On the straight line x + s d_lo every face of the star of x
//     projects along d_lo with positive orientation, so its star covers the projection of x with
//     degree k ≥ 1 and w drops by k across x; w ∈ {0, 1} forces k = 1 and w: 1 -> 0.
// (3) Between crossings w is constant along the fiber, each crossing lowers it by 1, w ∈ {0, 1}:
//     at most one crossing, and the fiber never runs inside the input (no segment overlap).
//
// Degenerate cases, as (1) handles them:
//  - A face lying in an internal facet (between two tets of one half, or the mid triangle between
//    the halves; e.g. the unsimplified shell's own face) meets no open tet, but meets the facet's
//    relative interior while coplanar: it is in C(P) and must pass the pillar test (it does, with
//    the orientation of the mid triangle; a reversed coplanar face would fail).
//  - A face across a sharp edge touching P only along the shared edge or at a vertex, i.e. on
//    the lateral boundary, without entering the neighbour's open tets either: not in C(P). A fiber
//    at such a point lies on the side quad or pillar shared with the neighbour, and (1) finds
//    that face in the neighbour's C. A face lying within a lateral facet (a side-quad triangle)
//    is in C(P) through the coplanar clause and fails: its normal is perpendicular to the pillar
//    in that facet, and a fiber would run inside it.
//  - Pinched prisms: the flat tets of a singular pillar are skipped; the others still cover P,
//    consecutive non-degenerate tets share the (coinciding) rising facet, and the singular pillar
//    is never a fiber direction of a non-degenerate tet.
// Closed contact with a tet that is neither of these (edge or vertex contact, or a transversal
// touch of a facet's boundary) is not section contact: no fiber of P meets the face there except
// fibers shared with a neighbour, which (1) checks in the neighbour.

using V3 = Eigen::Vector3d;

template <class NT>
NT det_of_differences(const V3& u1, const V3& u0, const V3& v1, const V3& v0, const V3& w1,
                      const V3& w0) {
  const NT ux = NT(u1.x()) - NT(u0.x()), uy = NT(u1.y()) - NT(u0.y()), uz = NT(u1.z()) - NT(u0.z());
  const NT vx = NT(v1.x()) - NT(v0.x()), vy = NT(v1.y()) - NT(v0.y()), vz = NT(v1.z()) - NT(v0.z());
  const NT wx = NT(w1.x()) - NT(w0.x()), wy = NT(w1.y()) - NT(w0.y()), wz = NT(w1.z()) - NT(w0.z());
  return ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx);
}

// Exact sign of det[u1 − u0, v1 − v0, w1 − w0] (interval filter, then CGAL::Mpzf: exact for
// sums and products of doubles, no division needed).
int sign_det(const V3& u1, const V3& u0, const V3& v1, const V3& v0, const V3& w1, const V3& w0) {
  // Columns that are zero or equal up to sign by identity of the points (shared vertices of the
  // shell and the input make these frequent): the determinant is exactly 0.
  auto same = [](const V3& p1, const V3& p0, const V3& q1, const V3& q0) {
    return (p1 == q1 && p0 == q0) || (p1 == q0 && p0 == q1);
  };
  if (u1 == u0 || v1 == v0 || w1 == w0 || same(u1, u0, v1, v0) || same(u1, u0, w1, w0) ||
      same(v1, v0, w1, w0))
    return 0;
  {
    // Static filter: Shewchuk's orient3d bound (7 + 56ε)ε · permanent holds for any three
    // rounded differences, as in orient3d. Outside the safe range (tiny or huge magnitudes) the
    // interval filter decides.
    const V3 u = u1 - u0, v = v1 - v0, w = w1 - w0;
    const double a = v.y() * w.z() - v.z() * w.y(), b = v.x() * w.z() - v.z() * w.x(),
                 c = v.x() * w.y() - v.y() * w.x();
    const double det = u.x() * a - u.y() * b + u.z() * c;
    const double permanent = std::abs(u.x()) * (std::abs(v.y() * w.z()) + std::abs(v.z() * w.y())) +
                             std::abs(u.y()) * (std::abs(v.x() * w.z()) + std::abs(v.z() * w.x())) +
                             std::abs(u.z()) * (std::abs(v.x() * w.y()) + std::abs(v.y() * w.x()));
    constexpr double eps = std::numeric_limits<double>::epsilon() / 2;
    if (permanent > 1e-250 && permanent < 1e250) {
      const double bound = (7.0 + 56.0 * eps) * eps * permanent;
      if (det > bound) return 1;
      if (det < -bound) return -1;
    }
  }
  {
    CGAL::Protect_FPU_rounding<true> guard;
    const CGAL::Interval_nt<false> d =
        det_of_differences<CGAL::Interval_nt<false>>(u1, u0, v1, v0, w1, w0);
    if (d.inf() > 0) return 1;
    if (d.sup() < 0) return -1;
    if (d.inf() == 0 && d.sup() == 0) return 0;
  }
  return int(CGAL::sign(det_of_differences<CGAL::Mpzf>(u1, u0, v1, v0, w1, w0)));
}

// The (i, j, k) facets of a tet with the opposite corner l.
constexpr int k_tet_facets[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};
// The (i, j) edges of a tet with the two other corners.
constexpr int k_tet_edges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2},
                                   {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};

}  // namespace

int normal_dot_sign(const std::array<V3, 3>& tri, const V3& from, const V3& to) {
  return sign_det(tri[1], tri[0], tri[2], tri[0], to, from);
}

// int(T) ∩ t = ∅ iff 0 ∉ int(T − t), i.e. iff some facet of the Minkowski difference T − t has
// 0 on its outer closed side: a plane weakly separating T and t. The facet normals of T − t are
// the facet normals of T, the normal of t, and the cross products of an edge of T with an edge
// of t, so testing these candidates is complete. A candidate counts only if some corner of T is
// strictly off it (a zero normal, from parallel edges or a degenerate t, puts every corner on it).
bool triangle_meets_open_tet(const std::array<V3, 3>& t, const std::array<V3, 4>& T) {
  for (const auto& f : k_tet_facets) {
    const V3 &a = T[f[0]], &b = T[f[1]], &c = T[f[2]];
    const int side = sign_det(b, a, c, a, T[f[3]], a);
    if (side == 0) return false;  // degenerate tet: no interior
    bool separated = true;
    for (const V3& q : t)
      if (sign_det(b, a, c, a, q, a) * side > 0) {
        separated = false;
        break;
      }
    if (separated) return false;
  }
  {
    int pos = 0, neg = 0;
    for (const V3& p : T) {
      const int s = sign_det(t[1], t[0], t[2], t[0], p, t[0]);
      pos += s > 0;
      neg += s < 0;
    }
    if ((pos == 0) != (neg == 0)) return false;
  }
  for (const auto& e : k_tet_edges) {
    const V3 &a = T[e[0]], &b = T[e[1]];
    for (int k = 0; k < 3; ++k) {
      const V3 &q0 = t[k], &q1 = t[(k + 1) % 3], &q2 = t[(k + 2) % 3];
      const int s1 = sign_det(b, a, q1, q0, T[e[2]], a), s2 = sign_det(b, a, q1, q0, T[e[3]], a);
      if ((s1 == 0 && s2 == 0) || s1 * s2 < 0) continue;
      const int side = s1 != 0 ? s1 : s2;
      // q0 and q1 lie on a line parallel to the plane: one sign for both.
      if (sign_det(b, a, q1, q0, q0, a) * side <= 0 && sign_det(b, a, q1, q0, q2, a) * side <= 0)
        return false;
    }
  }
  return true;
}

// Coplanar case in 2-D: project along an axis that keeps the facet non-degenerate (exact
// orient2d), then the same weak separating-axis test with the edge lines of both triangles.
bool triangle_meets_open_facet(const std::array<V3, 3>& t, const std::array<V3, 3>& F) {
  for (const V3& q : t)
    if (sign_det(F[1], F[0], F[2], F[0], q, F[0]) != 0) return false;
  using P2 = K::Point_2;
  for (int drop : {2, 0, 1}) {
    const int i = (drop + 1) % 3, j = (drop + 2) % 3;
    const std::array<P2, 3> f{P2(F[0][i], F[0][j]), P2(F[1][i], F[1][j]), P2(F[2][i], F[2][j])};
    if (CGAL::orientation(f[0], f[1], f[2]) == CGAL::COLLINEAR) continue;
    const std::array<P2, 3> q{P2(t[0][i], t[0][j]), P2(t[1][i], t[1][j]), P2(t[2][i], t[2][j])};
    for (int k = 0; k < 3; ++k) {
      const P2 &a = f[k], &b = f[(k + 1) % 3];
      const int side = int(CGAL::orientation(a, b, f[(k + 2) % 3]));
      bool separated = true;
      for (const P2& p : q)
        if (int(CGAL::orientation(a, b, p)) * side > 0) {
          separated = false;
          break;
        }
      if (separated) return false;
    }
    for (int k = 0; k < 3; ++k) {
      const P2 &a = q[k], &b = q[(k + 1) % 3];
      int pos = 0, neg = 0;
      for (const P2& p : f) {
        const int s = int(CGAL::orientation(a, b, p));
        pos += s > 0;
        neg += s < 0;
      }
      if ((pos == 0) == (neg == 0)) continue;  // zero edge, or the facet on both sides
      const int side = pos > 0 ? 1 : -1;
      if (int(CGAL::orientation(a, b, q[(k + 2) % 3])) * side <= 0) return false;
    }
    return true;
  }
  return false;  // degenerate facet: no relative interior
}

bool triangle_section_contact(const std::array<V3, 3>& t, const std::array<V3, 4>& T) {
  for (int k = 0; k < 3; ++k) {  // bounding boxes (exact comparisons)
    const double tlo = std::min({t[0][k], t[1][k], t[2][k]}),
                 thi = std::max({t[0][k], t[1][k], t[2][k]});
    const double lo = std::min({T[0][k], T[1][k], T[2][k], T[3][k]}),
                 hi = std::max({T[0][k], T[1][k], T[2][k], T[3][k]});
    if (thi < lo || tlo > hi) return false;  // no contact (a face in a facet plane touches)
  }
  if (triangle_meets_open_tet(t, T)) return true;
  for (const auto& f : k_tet_facets)
    if (triangle_meets_open_facet(t, {T[f[0]], T[f[1]], T[f[2]]})) return true;
  return false;
}

bool segment_crosses_wedge(const V3& p, const V3& q, const V3& apex, const V3& a, const V3& b) {
  if (CGAL::collinear(pt(apex), pt(a), pt(b))) return false;
  const int sp = sign_det(a, apex, b, apex, p, apex), sq = sign_det(a, apex, b, apex, q, apex);
  if ((sp == 0 && sq == 0) || sp * sq > 0) return false;
  // The line p→q meets the plane at x. det[q − p, apex − p, a − p] and det[q − p, b − p, apex − p]
  // have the sign of the crossing direction (`dir`) where x is strictly inside the wedge, are 0 on
  // the line of apex–a (apex–b), and change sign across it: both signs agreeing with `dir` (or 0)
  // put x in the intersection of two half-planes through the apex, which is the wedge.
  const int dir = sq != 0 ? sq : -sp;
  return sign_det(q, p, apex, p, a, p) * dir >= 0 && sign_det(q, p, b, p, apex, p) * dir >= 0;
}

struct InputSurfaceIndex::Impl {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  std::vector<Triangle> triangles;
  std::vector<CGAL::Bbox_3> boxes;  // of `triangles`
  Tree tree;
  int id(const std::vector<Triangle>::const_iterator& it) const {
    return int(it - triangles.cbegin());
  }
};

InputSurfaceIndex::InputSurfaceIndex(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F)
    : m_impl(std::make_unique<Impl>()) {
  m_impl->V = V;
  m_impl->F = F;
  m_impl->triangles.reserve(F.rows());
  for (int f = 0; f < F.rows(); ++f)
    m_impl->triangles.emplace_back(pt(V.row(F(f, 0))), pt(V.row(F(f, 1))), pt(V.row(F(f, 2))));
  m_impl->boxes.reserve(F.rows());
  for (const Triangle& t : m_impl->triangles) m_impl->boxes.push_back(t.bbox());
  m_impl->tree.insert(m_impl->triangles.cbegin(), m_impl->triangles.cend());
  m_impl->tree.build();
  m_impl->tree.accelerate_distance_queries();
}

InputSurfaceIndex::~InputSurfaceIndex() = default;
const Eigen::MatrixXd& InputSurfaceIndex::V() const { return m_impl->V; }
const Eigen::MatrixXi& InputSurfaceIndex::F() const { return m_impl->F; }

double InputSurfaceIndex::ray_distance(const Eigen::Vector3d& origin,
                                       const Eigen::Vector3d& direction,
                                       const std::vector<int>& ignore) const {
  const K::Ray_3 ray(pt(origin), K::Vector_3(direction.x(), direction.y(), direction.z()));
  auto skip = [&](const std::vector<Triangle>::const_iterator& it) {
    return std::find(ignore.begin(), ignore.end(), m_impl->id(it)) != ignore.end();
  };
  const auto hit = m_impl->tree.first_intersection(ray, skip);
  if (!hit) return std::numeric_limits<double>::infinity();
  if (const Point* p = boost::get<Point>(&hit->first))
    return std::sqrt(CGAL::to_double(CGAL::squared_distance(*p, ray.source())));
  if (const Segment* s = boost::get<Segment>(&hit->first))
    return std::sqrt(std::min(CGAL::to_double(CGAL::squared_distance(s->source(), ray.source())),
                              CGAL::to_double(CGAL::squared_distance(s->target(), ray.source()))));
  return 0.0;
}

bool triangles_meet_beyond_pinch(const std::array<V3, 3>& a, int ka, const std::array<V3, 3>& b,
                                 int kb) {
  const Triangle ta(pt(a[0]), pt(a[1]), pt(a[2])), tb(pt(b[0]), pt(b[1]), pt(b[2]));
  if (ka < 0 || kb < 0) return CGAL::do_intersect(ta, tb);
  // Contact at the shared point only: neither opposite edge touches the other triangle.
  const Segment mine(ta[(ka + 1) % 3], ta[(ka + 2) % 3]),
      theirs(tb[(kb + 1) % 3], tb[(kb + 2) % 3]);
  if (CGAL::do_intersect(mine, tb) || CGAL::do_intersect(theirs, ta)) return true;
  return CGAL::coplanar(ta[0], ta[1], ta[2], tb[0]) && CGAL::coplanar(ta[0], ta[1], ta[2], tb[1]) &&
         CGAL::coplanar(ta[0], ta[1], ta[2], tb[2]);  // coplanar fans: conservatively meeting
}

bool InputSurfaceIndex::triangle_intersects(const std::array<Eigen::Vector3d, 3>& c,
                                            const std::array<bool, 3>& singular,
                                            const Eigen::Vector3i& corner_ids) const {
  const Triangle tri(pt(c[0]), pt(c[1]), pt(c[2]));
  if (tri.is_degenerate()) return true;  // never accept a flat base/top triangle
  std::vector<std::vector<Triangle>::const_iterator> hits;
  m_impl->tree.all_intersected_primitives(tri, std::back_inserter(hits));
  for (const auto& it : hits) {
    const int f = m_impl->id(it);
    int pinch = -1, shared = -1;  // the triangle's corner at a singular input vertex of face f
    for (int k = 0; k < 3; ++k)
      if (singular[k])
        for (int j = 0; j < 3; ++j)
          if (m_impl->F(f, j) == corner_ids[k]) {
            pinch = k;
            shared = j;
          }
    if (pinch < 0 || triangles_meet_beyond_pinch(c, pinch, face_triangle(f), shared)) return true;
  }
  return false;
}

namespace {
// True if a plane strictly separates the closed triangle from the closed tet: one of the tet's
// facet planes with all three triangle corners strictly outside, or the triangle's plane with
// all four tet corners strictly on one side. Exact (filtered orientation predicates); a cheap
// rejection before CGAL's general triangle-tetrahedron test, which most bounding-box candidates
// would otherwise pay for in interval arithmetic.
bool strictly_separated(const Triangle& tri, const K::Tetrahedron_3& tet) {
  static constexpr int facet[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (int j = 0; j < 4; ++j) {
    const Point &a = tet[facet[j][0]], &b = tet[facet[j][1]], &c = tet[facet[j][2]];
    const auto inside = CGAL::orientation(a, b, c, tet[j]);
    if (inside == CGAL::COPLANAR) continue;
    bool all_out = true;
    for (int k = 0; k < 3 && all_out; ++k) all_out = CGAL::orientation(a, b, c, tri[k]) == -inside;
    if (all_out) return true;
  }
  const auto s0 = CGAL::orientation(tri[0], tri[1], tri[2], tet[0]);
  if (s0 == CGAL::COPLANAR) return false;
  for (int j = 1; j < 4; ++j)
    if (CGAL::orientation(tri[0], tri[1], tri[2], tet[j]) != s0) return false;
  return true;
}
}  // namespace

namespace {
// Traversal traits for AABB_tree::traversal (a CGAL-internal entry point, stable in the CGAL 5.5
// of Debian 12) listing the primitives whose bounding box overlaps a query box. The tree's own
// box query tests each candidate triangle against the box exactly, work the callers here redo
// with the real shape anyway.
struct BoxOverlapTraits {
  const std::vector<Triangle>* triangles;
  const std::vector<CGAL::Bbox_3>* boxes;
  std::vector<int>* out;
  bool go_further() const { return true; }
  void intersection(const CGAL::Bbox_3& q, const Primitive& p) {
    const int f = int(p.id() - triangles->cbegin());
    if (CGAL::do_overlap(q, (*boxes)[std::size_t(f)])) out->push_back(f);
  }
  template <class Node>
  bool do_intersect(const CGAL::Bbox_3& q, const Node& node) const {
    return CGAL::do_overlap(q, node.bbox());
  }
};
}  // namespace

std::vector<int> InputSurfaceIndex::faces_touching_tets(
    const std::vector<std::array<Eigen::Vector3d, 4>>& tets) const {
  std::vector<int> out;
  if (tets.empty()) return out;
  std::vector<K::Tetrahedron_3> T;
  std::vector<CGAL::Bbox_3> tb;
  CGAL::Bbox_3 all;
  for (const auto& t : tets) {
    T.emplace_back(pt(t[0]), pt(t[1]), pt(t[2]), pt(t[3]));
    tb.push_back(T.back().bbox());
    all += tb.back();
  }
  std::vector<int> candidates;
  BoxOverlapTraits traits{&m_impl->triangles, &m_impl->boxes, &candidates};
  m_impl->tree.traversal(all, traits);
  for (int f : candidates) {
    const Triangle& tri = m_impl->triangles[std::size_t(f)];
    const CGAL::Bbox_3& fb = m_impl->boxes[std::size_t(f)];
    for (std::size_t i = 0; i < T.size(); ++i) {
      if (!CGAL::do_overlap(fb, tb[i])) continue;
      // A triangle corner that IS a tet corner touches the closed tet: decided without the exact
      // fallback CGAL's filtered predicate takes for such degenerate contacts (the shell's middle
      // surface starts on the input vertices, so they are the common case).
      bool shared = false;
      for (int a = 0; a < 3 && !shared; ++a)
        for (int j = 0; j < 4 && !shared; ++j) shared = tri.vertex(a) == T[i].vertex(j);
      if (shared || (!strictly_separated(tri, T[i]) && CGAL::do_intersect(tri, T[i]))) {
        out.push_back(f);
        break;
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<int> InputSurfaceIndex::faces_touching_tet(
    const std::array<Eigen::Vector3d, 4>& t) const {
  return faces_touching_tets({t});
}

std::vector<int> InputSurfaceIndex::faces_in_box(const Eigen::Vector3d& lo,
                                                 const Eigen::Vector3d& hi) const {
  const CGAL::Bbox_3 box(lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
  std::vector<std::vector<Triangle>::const_iterator> hits;
  m_impl->tree.all_intersected_primitives(box, std::back_inserter(hits));
  std::vector<int> out;
  out.reserve(hits.size());
  for (const auto& it : hits) out.push_back(m_impl->id(it));
  return out;
}

std::vector<int> InputSurfaceIndex::faces_containing(const Eigen::Vector3d& p) const {
  std::vector<int> out;
  for (int f : faces_in_box(p, p)) {
    const Triangle& t = m_impl->triangles[std::size_t(f)];
    if (t.is_degenerate()) continue;
    bool corner = false;
    for (int k = 0; k < 3; ++k) corner |= m_impl->V.row(m_impl->F(f, k)) == p.transpose();
    if (corner || t.has_on(pt(p))) out.push_back(f);
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool InputSurfaceIndex::face_touches_tet(int f, const std::array<Eigen::Vector3d, 4>& t) const {
  const K::Tetrahedron_3 tet(pt(t[0]), pt(t[1]), pt(t[2]), pt(t[3]));
  const Triangle& tri = m_impl->triangles[std::size_t(f)];
  return !strictly_separated(tri, tet) && CGAL::do_intersect(tri, tet);
}

bool InputSurfaceIndex::face_section_contact(int f, const std::array<Eigen::Vector3d, 4>& t) const {
  return triangle_section_contact(face_triangle(f), t);
}

std::array<Eigen::Vector3d, 3> InputSurfaceIndex::face_triangle(int f) const {
  return {m_impl->V.row(m_impl->F(f, 0)).transpose(), m_impl->V.row(m_impl->F(f, 1)).transpose(),
          m_impl->V.row(m_impl->F(f, 2)).transpose()};
}

int InputSurfaceIndex::closest_face(const Eigen::Vector3d& p, Eigen::Vector3d& closest) const {
  const auto [q, it] = m_impl->tree.closest_point_and_primitive(pt(p));
  closest = Eigen::Vector3d(q.x(), q.y(), q.z());
  return m_impl->id(it);
}

int InputSurfaceIndex::segment_hit(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   Eigen::Vector3d& bary) const {
  const Segment seg(pt(a), pt(b));
  std::vector<std::vector<Triangle>::const_iterator> hits;
  m_impl->tree.all_intersected_primitives(seg, std::back_inserter(hits));
  int best = -1;
  double best_t = std::numeric_limits<double>::infinity();
  for (const auto& it : hits) {
    const int f = m_impl->id(it);
    const Eigen::Vector3d p0 = m_impl->V.row(m_impl->F(f, 0)), p1 = m_impl->V.row(m_impl->F(f, 1)),
                          p2 = m_impl->V.row(m_impl->F(f, 2));
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    const double denom = n.dot(b - a);
    double t = 0.0;
    if (std::abs(denom) > 0) t = std::clamp(n.dot(p0 - a) / denom, 0.0, 1.0);
    if (t >= best_t) continue;
    const Eigen::Vector3d x = a + t * (b - a);
    const double area = n.squaredNorm();
    Eigen::Vector3d w;
    w[1] = n.dot((x - p0).cross(p2 - p0)) / area;
    w[2] = n.dot((p1 - p0).cross(x - p0)) / area;
    w[0] = 1.0 - w[1] - w[2];
    best = f;
    best_t = t;
    bary = w;
  }
  return best;
}

}  // namespace curvefem::meshing::shell
