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
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <unordered_map>

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

// ---- Snapped points (the reference copy of feature chains) ---------------------------------
// A snapped point is a + s (b − a) with double a, b, s: its coordinates are sums and products of
// doubles, so the interval filter encloses them and CGAL::Mpzf evaluates them exactly.
template <class NT>
NT coord(const ExactPoint& q, int k) {
  if (!q.snapped) return NT(q.p[k]);
  return NT(q.a[k]) + NT(q.s) * (NT(q.b[k]) - NT(q.a[k]));
}
template <class NT>
NT det_of_differences(const ExactPoint& u1, const ExactPoint& u0, const ExactPoint& v1,
                      const ExactPoint& v0, const ExactPoint& w1, const ExactPoint& w0) {
  NT u[3], v[3], w[3];
  for (int k = 0; k < 3; ++k) {
    u[k] = coord<NT>(u1, k) - coord<NT>(u0, k);
    v[k] = coord<NT>(v1, k) - coord<NT>(v0, k);
    w[k] = coord<NT>(w1, k) - coord<NT>(w0, k);
  }
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
         u[2] * (v[0] * w[1] - v[1] * w[0]);
}
// det(u1 − u0, v1 − v0, w1 − w0) is affine in each of its six arguments, so a snapped argument
// a + s (b − a) with 0 < s < 1 splits it into (1 − s) det(…a…) + s det(…b…), both weights
// positive. Expanding every snapped argument (at most 8 terms here) gives a sum of double
// determinants with positive weights: where no two terms have opposite signs, the sum has the
// sign of its nonzero terms, and is exactly 0 when all are. The terms are exact double
// predicates, so this decides exactly, and cheaply, the degenerate configurations chains make
// (a snapped point on the coarse edge its chain lies on) without rational arithmetic.
// Returns 2 when the terms disagree (or s is outside [0, 1], or too many arguments are snapped).
int expanded_sign(const std::array<const ExactPoint*, 6>& q) {
  std::array<std::array<const V3*, 2>, 6> options{};
  std::array<int, 6> count{};
  int terms = 1;
  for (int i = 0; i < 6; ++i) {
    const ExactPoint& x = *q[std::size_t(i)];
    auto& o = options[std::size_t(i)];
    int& c = count[std::size_t(i)];
    if (!x.snapped) {
      o[0] = &x.p;
      c = 1;
    } else if (x.s == 0) {
      o[0] = &x.a;  // a + 0 (b − a) = a exactly
      c = 1;
    } else if (x.s == 1) {
      o[0] = &x.b;  // a + (b − a) = b exactly
      c = 1;
    } else if (x.s > 0 && x.s < 1) {
      o[0] = &x.a;
      o[1] = &x.b;
      c = 2;
    } else {
      return 2;
    }
    terms *= c;
  }
  if (terms > 8) return 2;
  bool pos = false, neg = false;
  for (int t = 0; t < terms; ++t) {
    std::array<const V3*, 6> p{};
    int rest = t;
    for (int i = 0; i < 6; ++i) {
      p[std::size_t(i)] = options[std::size_t(i)][std::size_t(rest % count[std::size_t(i)])];
      rest /= count[std::size_t(i)];
    }
    const int s = sign_det(*p[0], *p[1], *p[2], *p[3], *p[4], *p[5]);
    pos = pos || s > 0;
    neg = neg || s < 0;
    if (pos && neg) return 2;
  }
  return pos ? 1 : (neg ? -1 : 0);
}
// A column q1 − q0 whose points lie on one snapped segment a–b is a known multiple of b − a:
// both snapped on it, (s1 − s0)(b − a); q1 snapped and q0 = a, s1 (b − a); q1 snapped and q0 = b,
// (1 − s1)(a − b); and the same with the roles swapped (negated). The sign of the factor is
// exact (a comparison of doubles), so the column becomes the plain pair (b, a) and the factor's
// sign multiplies the determinant. Returns that sign (0: the column is exactly zero), the pair
// in `out`; 2 where no such rule applies (the column is kept).
int simplified_column(const ExactPoint& q1, const ExactPoint& q0,
                      std::array<const ExactPoint*, 2>& out, ExactPoint& b_store,
                      ExactPoint& a_store) {
  auto on_segment_of = [](const ExactPoint& snapped, const ExactPoint& plain) {
    return !plain.snapped && (plain.p == snapped.a || plain.p == snapped.b);
  };
  int sign = 2;
  const ExactPoint* seg = nullptr;
  if (q1.snapped && q0.snapped) {
    if (q1.a != q0.a || q1.b != q0.b) return 2;
    sign = q1.s > q0.s ? 1 : (q1.s < q0.s ? -1 : 0);
    seg = &q1;
  } else if (q1.snapped && on_segment_of(q1, q0)) {
    // q1 − a = s1 (b − a); q1 − b = (1 − s1)(a − b) = −(1 − s1)(b − a).
    if (!(q1.s >= 0 && q1.s <= 1)) return 2;
    sign = q0.p == q1.a ? (q1.s > 0 ? 1 : 0) : (q1.s < 1 ? -1 : 0);
    seg = &q1;
  } else if (q0.snapped && on_segment_of(q0, q1)) {
    if (!(q0.s >= 0 && q0.s <= 1)) return 2;
    sign = q1.p == q0.a ? (q0.s > 0 ? -1 : 0) : (q0.s < 1 ? 1 : 0);
    seg = &q0;
  } else {
    return 2;
  }
  if (seg->a == seg->b) return 0;
  b_store = ExactPoint(seg->b);
  a_store = ExactPoint(seg->a);
  out = {&b_store, &a_store};
  return sign;
}
// A floating-point filter with snapped arguments: the determinant of the rounded points, each
// snapped one recomputed here as a + s (b − a) (for s in [0, 1] every coordinate is then within
// 4u (|a|∞ + |b|∞) of the exact point, u the unit roundoff: three roundings of terms bounded
// by |a| + |b|), decided when it exceeds the evaluation bound of sign_det's static filter plus
// a bound on what moving the points to their exact positions can change: a column c moves by
// at most √3 e_c in length (e_c the sum of its two points' coordinate errors), and by
// multilinearity and Hadamard's inequality |det(c + dc) − det(c)| is at most the sum over the
// non-empty subsets S of the columns of the products of |dc| over S and |c| off S. Returns 2
// where it cannot decide (near-degenerate configurations, e.g. a point snapped onto the line
// of the others, which the exact stages below handle).
int filtered_snapped_sign(const std::array<const ExactPoint*, 6>& q) {
  constexpr double u = std::numeric_limits<double>::epsilon() / 2;
  std::array<V3, 6> p;
  std::array<double, 6> e{};
  for (std::size_t i = 0; i < 6; ++i) {
    const ExactPoint& x = *q[i];
    if (!x.snapped) {
      p[i] = x.p;
      continue;
    }
    if (!(x.s >= 0 && x.s <= 1)) return 2;
    p[i] = x.a + x.s * (x.b - x.a);
    e[i] = 4 * u * (x.a.cwiseAbs().maxCoeff() + x.b.cwiseAbs().maxCoeff());
  }
  const V3 cu = p[0] - p[1], cv = p[2] - p[3], cw = p[4] - p[5];
  const double a = cv.y() * cw.z() - cv.z() * cw.y(), b = cv.x() * cw.z() - cv.z() * cw.x(),
               c = cv.x() * cw.y() - cv.y() * cw.x();
  const double det = cu.x() * a - cu.y() * b + cu.z() * c;
  const double permanent =
      std::abs(cu.x()) * (std::abs(cv.y() * cw.z()) + std::abs(cv.z() * cw.y())) +
      std::abs(cu.y()) * (std::abs(cv.x() * cw.z()) + std::abs(cv.z() * cw.x())) +
      std::abs(cu.z()) * (std::abs(cv.x() * cw.y()) + std::abs(cv.y() * cw.x()));
  if (!(permanent > 1e-250 && permanent < 1e250)) return 2;
  // Column lengths and their possible changes, rounded up generously (each computed value is
  // within a few u of its exact one).
  constexpr double up = 1 + 1e-10;
  const double nu = cu.norm() * up, nv = cv.norm() * up, nw = cw.norm() * up;
  const double du = std::sqrt(3.0) * (e[0] + e[1]) * up, dv = std::sqrt(3.0) * (e[2] + e[3]) * up,
               dw = std::sqrt(3.0) * (e[4] + e[5]) * up;
  const double moved = (du * nv * nw + nu * dv * nw + nu * nv * dw + du * dv * nw + du * nv * dw +
                        nu * dv * dw + du * dv * dw) *
                       up;
  // The rounded differences of sign_det's filter: their error is inside its bound, whose
  // permanent is taken of the rounded columns, as there.
  const double bound = (7.0 + 56.0 * u) * u * permanent * up + moved;
  if (!(bound < 1e250)) return 2;
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return 2;
}
int sign_det(const ExactPoint& u1, const ExactPoint& u0, const ExactPoint& v1, const ExactPoint& v0,
             const ExactPoint& w1, const ExactPoint& w0) {
  if (!u1.snapped && !u0.snapped && !v1.snapped && !v0.snapped && !w1.snapped && !w0.snapped)
    return sign_det(u1.p, u0.p, v1.p, v0.p, w1.p, w0.p);
  if (const int s = filtered_snapped_sign({&u1, &u0, &v1, &v0, &w1, &w0}); s != 2) return s;
  {
    std::array<const ExactPoint*, 6> q{&u1, &u0, &v1, &v0, &w1, &w0};
    std::array<ExactPoint, 6> store;
    int factor = 1;
    for (std::size_t c = 0; c < 3; ++c) {
      std::array<const ExactPoint*, 2> pair{};
      const int s =
          simplified_column(*q[2 * c], *q[2 * c + 1], pair, store[2 * c], store[2 * c + 1]);
      if (s == 0) return 0;
      if (s == 2) continue;
      factor *= s;
      q[2 * c] = pair[0];
      q[2 * c + 1] = pair[1];
    }
    if (const int s = expanded_sign(q); s != 2) return factor * s;
  }
  {
    CGAL::Protect_FPU_rounding<true> guard;
    const CGAL::Interval_nt<false> d =
        det_of_differences<CGAL::Interval_nt<false>>(u1, u0, v1, v0, w1, w0);
    if (d.inf() > 0) return 1;
    if (d.sup() < 0) return -1;
  }
  return int(CGAL::sign(det_of_differences<CGAL::Mpzf>(u1, u0, v1, v0, w1, w0)));
}
// All-double arguments take the filtered double version; any snapped one the version above.
template <class A, class B, class C, class D, class E, class F>
int sdet(const A& u1, const B& u0, const C& v1, const D& v0, const E& w1, const F& w0) {
  if constexpr (std::is_same_v<A, V3> && std::is_same_v<B, V3> && std::is_same_v<C, V3> &&
                std::is_same_v<D, V3> && std::is_same_v<E, V3> && std::is_same_v<F, V3>)
    return sign_det(u1, u0, v1, v0, w1, w0);
  else
    return sign_det(ExactPoint(u1), ExactPoint(u0), ExactPoint(v1), ExactPoint(v0), ExactPoint(w1),
                    ExactPoint(w0));
}
// The point with coordinate `drop` set to 0 (exact for snapped points too: a and b are).
template <class P>
P dropped(const P& q, int drop) {
  P out = q;
  if constexpr (std::is_same_v<P, V3>) {
    out[drop] = 0;
  } else {
    out.p[drop] = 0;
    out.a[drop] = 0;
    out.b[drop] = 0;
  }
  return out;
}
// orient2d of (a, b, c) in the coordinates ((drop + 1) % 3, (drop + 2) % 3): det[b − a, c − a,
// e_drop] of the points with coordinate `drop` zeroed.
template <class P, class Q, class R>
int orient2(int drop, const P& a, const Q& b, const R& c) {
  V3 e = V3::Zero();
  e[drop] = 1;
  const P a0 = dropped(a, drop);
  return sdet(dropped(b, drop), a0, dropped(c, drop), a0, e, V3(V3::Zero()));
}

}  // namespace

ExactPoint ExactPoint::on_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double s) {
  ExactPoint q(a + s * (b - a));
  q.snapped = true;
  q.a = a;
  q.b = b;
  q.s = s;
  return q;
}

int normal_dot_sign(const std::array<V3, 3>& tri, const V3& from, const V3& to) {
  return sign_det(tri[1], tri[0], tri[2], tri[0], to, from);
}

int exact_normal_dot_sign(const std::array<ExactPoint, 3>& tri, const V3& from, const V3& to) {
  return sdet(tri[1], tri[0], tri[2], tri[0], to, from);
}

bool exact_collinear(const std::array<ExactPoint, 3>& t) {
  for (int drop = 0; drop < 3; ++drop)
    if (orient2(drop, t[0], t[1], t[2]) != 0) return false;
  return true;
}

namespace {

// int(T) ∩ t = ∅ iff 0 ∉ int(T − t), i.e. iff some facet of the Minkowski difference T − t has
// 0 on its outer closed side: a plane weakly separating T and t. The facet normals of T − t are
// the facet normals of T, the normal of t, and the cross products of an edge of T with an edge
// of t, so testing these candidates is complete. A candidate counts only if some corner of T is
// strictly off it (a zero normal, from parallel edges or a degenerate t, puts every corner on it).
// Closed (`closed`): the closed sets are disjoint iff 0 lies strictly outside a facet of T − t,
// so the same candidates, each through the tet's supporting facet or edge (or the triangle's
// plane), separate only with the other set strictly beyond them.
template <bool closed, class P>
bool meets_tet(const std::array<P, 3>& t, const std::array<V3, 4>& T) {
  // "beyond" a plane on the side opposite to `side`: strictly for the closed test, weakly for
  // the open one.
  auto beyond = [](int s, int side) { return closed ? s * side < 0 : s * side <= 0; };
  for (const auto& f : k_tet_facets) {
    const V3 &a = T[f[0]], &b = T[f[1]], &c = T[f[2]];
    const int side = sign_det(b, a, c, a, T[f[3]], a);
    if (side == 0) return closed;  // degenerate tet (never passed; conservative when closed)
    bool separated = true;
    for (const P& q : t)
      if (!beyond(sdet(b, a, c, a, q, a), side)) {
        separated = false;
        break;
      }
    if (separated) return false;
  }
  {
    int pos = 0, neg = 0;
    for (const V3& p : T) {
      const int s = sdet(t[1], t[0], t[2], t[0], p, t[0]);
      pos += s > 0;
      neg += s < 0;
    }
    if (closed ? (pos == 4 || neg == 4) : ((pos == 0) != (neg == 0))) return false;
  }
  for (const auto& e : k_tet_edges) {
    const V3 &a = T[e[0]], &b = T[e[1]];
    for (int k = 0; k < 3; ++k) {
      const P &q0 = t[k], &q1 = t[(k + 1) % 3], &q2 = t[(k + 2) % 3];
      const int s1 = sdet(b, a, q1, q0, T[e[2]], a), s2 = sdet(b, a, q1, q0, T[e[3]], a);
      if ((s1 == 0 && s2 == 0) || s1 * s2 < 0) continue;
      const int side = s1 != 0 ? s1 : s2;
      // q0 and q1 lie on a line parallel to the plane: one sign for both.
      if (beyond(sdet(b, a, q1, q0, q0, a), side) && beyond(sdet(b, a, q1, q0, q2, a), side))
        return false;
    }
  }
  return true;
}

// Coplanar case in 2-D: project along an axis that keeps the facet non-degenerate (exact
// orient2d), then the same weak separating-axis test with the edge lines of both triangles.
template <class P>
bool meets_open_facet(const std::array<P, 3>& t, const std::array<V3, 3>& F) {
  for (const P& q : t)
    if (sdet(F[1], F[0], F[2], F[0], q, F[0]) != 0) return false;
  for (int drop : {2, 0, 1}) {
    if (orient2(drop, F[0], F[1], F[2]) == 0) continue;
    for (int k = 0; k < 3; ++k) {
      const V3 &a = F[k], &b = F[(k + 1) % 3];
      const int side = orient2(drop, a, b, F[(k + 2) % 3]);
      bool separated = true;
      for (const P& p : t)
        if (orient2(drop, a, b, p) * side > 0) {
          separated = false;
          break;
        }
      if (separated) return false;
    }
    for (int k = 0; k < 3; ++k) {
      const P &a = t[k], &b = t[(k + 1) % 3];
      int pos = 0, neg = 0;
      for (const V3& p : F) {
        const int s = orient2(drop, a, b, p);
        pos += s > 0;
        neg += s < 0;
      }
      if ((pos == 0) == (neg == 0)) continue;  // zero edge, or the facet on both sides
      const int side = pos > 0 ? 1 : -1;
      if (orient2(drop, a, b, t[(k + 2) % 3]) * side <= 0) return false;
    }
    return true;
  }
  return false;  // degenerate facet: no relative interior
}

template <class P>
bool section_contact(const std::array<P, 3>& t, const std::array<V3, 4>& T) {
  if constexpr (std::is_same_v<P, V3>) {
    for (int k = 0; k < 3; ++k) {  // bounding boxes (exact comparisons)
      const double tlo = std::min({t[0][k], t[1][k], t[2][k]}),
                   thi = std::max({t[0][k], t[1][k], t[2][k]});
      const double lo = std::min({T[0][k], T[1][k], T[2][k], T[3][k]}),
                   hi = std::max({T[0][k], T[1][k], T[2][k], T[3][k]});
      if (thi < lo || tlo > hi) return false;  // no contact (a face in a facet plane touches)
    }
  }
  if (meets_tet<false>(t, T)) return true;
  for (const auto& f : k_tet_facets)
    if (meets_open_facet(t, {T[f[0]], T[f[1]], T[f[2]]})) return true;
  return false;
}

// Closed triangles, a against b, by the separating planes of their normals and of the 9 edge
// pairs (each through a's edge, b strictly beyond it); coplanar triangles count as meeting.
template <class P>
bool triangles_meet_closed(const std::array<P, 3>& a, const std::array<V3, 3>& b) {
  {
    int pos = 0, neg = 0;
    for (const V3& q : b) {
      const int s = sdet(a[1], a[0], a[2], a[0], q, a[0]);
      pos += s > 0;
      neg += s < 0;
    }
    if (pos == 3 || neg == 3) return false;
    if (pos == 0 && neg == 0) return true;  // coplanar (conservative)
  }
  {
    int pos = 0, neg = 0;
    for (const P& q : a) {
      const int s = sdet(b[1], b[0], b[2], b[0], q, b[0]);
      pos += s > 0;
      neg += s < 0;
    }
    if (pos == 3 || neg == 3) return false;
  }
  for (int i = 0; i < 3; ++i) {
    const P &p0 = a[i], &p1 = a[(i + 1) % 3], &p2 = a[(i + 2) % 3];
    for (int j = 0; j < 3; ++j) {
      const V3 &q0 = b[j], &q1 = b[(j + 1) % 3], &q2 = b[(j + 2) % 3];
      const int sa = sdet(p1, p0, q1, q0, p2, p0);
      const int s0 = sdet(p1, p0, q1, q0, q0, p0), s2 = sdet(p1, p0, q1, q0, q2, p0);
      if (s0 == 0 || s0 != s2) continue;
      if (sa == 0 || sa == -s0) return false;
    }
  }
  return true;
}

}  // namespace

bool triangle_meets_open_tet(const std::array<V3, 3>& t, const std::array<V3, 4>& T) {
  return meets_tet<false>(t, T);
}
bool triangle_meets_open_facet(const std::array<V3, 3>& t, const std::array<V3, 3>& F) {
  return meets_open_facet(t, F);
}
bool triangle_section_contact(const std::array<V3, 3>& t, const std::array<V3, 4>& T) {
  return section_contact(t, T);
}
// The orientation of each corner of T against its opposite facet (k_tet_facets order): the side
// a point of the closed tet is on, or 0 for all four when T is degenerate.
std::array<int, 4> tet_sides(const std::array<V3, 4>& T) {
  std::array<int, 4> side{};
  for (std::size_t j = 0; j < 4; ++j) {
    const auto& f = k_tet_facets[j];
    const V3& a = T[std::size_t(f[0])];
    side[j] = sign_det(T[std::size_t(f[1])], a, T[std::size_t(f[2])], a, T[std::size_t(f[3])], a);
    if (side[j] == 0) return {0, 0, 0, 0};
  }
  return side;
}
// Does a corner of tri lie in the closed tet T (sides: tet_sides(T))? Exact; false for a
// degenerate T. A sufficient condition for meets_tet<true>, far cheaper where it holds: a few
// orientations of one point instead of the separating-plane search, which must try every
// candidate plane before it can answer "meets" (the common answer in faces_touching_tets, whose
// candidates mostly lie in the prism).
bool corner_in_closed_tet(const std::array<ExactPoint, 3>& tri, const std::array<V3, 4>& T,
                          const std::array<int, 4>& side) {
  if (side[0] == 0) return false;
  for (const ExactPoint& q : tri) {
    bool inside = true;
    for (std::size_t j = 0; j < 4 && inside; ++j) {
      const auto& f = k_tet_facets[j];
      const V3& a = T[std::size_t(f[0])];
      const int s = sdet(T[std::size_t(f[1])], a, T[std::size_t(f[2])], a, q, a);
      inside = s == 0 || s == side[j];
    }
    if (inside) return true;
  }
  return false;
}
bool exact_triangle_meets_tet(const std::array<ExactPoint, 3>& tri, const std::array<V3, 4>& tet) {
  // A corner that is a tet corner touches the closed tet (the coarse corners of a chain are
  // input vertices, so the faces around them share corners with their prisms' tets).
  for (const ExactPoint& q : tri)
    if (!q.snapped)
      for (const V3& c : tet)
        if (q.p == c) return true;
  return corner_in_closed_tet(tri, tet, tet_sides(tet)) || meets_tet<true>(tri, tet);
}
bool exact_triangles_meet(const std::array<ExactPoint, 3>& a, const std::array<V3, 3>& b) {
  return triangles_meet_closed(a, b);
}
bool exact_section_contact(const std::array<ExactPoint, 3>& tri, const std::array<V3, 4>& tet) {
  return section_contact(tri, tet);
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
  // The reference copy: rounded positions, the snaps (vertex -1: not snapped) and the faces with
  // a snapped corner (`moved`, with each face's place in it or -1 and its snapped corner count).
  Eigen::MatrixXd Vref;
  std::vector<SnappedVertex> snap;
  std::vector<CGAL::Bbox_3> snap_box;  // enclosure of each snapped point
  std::vector<int> moved, moved_at, moved_corners;
  std::vector<std::vector<int>> vf;  // vertex -> faces (built at the first snap)
  bool is_moved(int f) const { return !moved_at.empty() && moved_at[std::size_t(f)] >= 0; }
  Eigen::Vector3d end_a(const SnappedVertex& q) const {
    return q.a >= 0 ? Eigen::Vector3d(V.row(q.a).transpose()) : q.pa;
  }
  Eigen::Vector3d end_b(const SnappedVertex& q) const {
    return q.b >= 0 ? Eigen::Vector3d(V.row(q.b).transpose()) : q.pb;
  }
  ExactPoint corner(int f, int k) const {
    const int x = F(f, k);
    if (!snap.empty() && snap[std::size_t(x)].vertex >= 0) {
      const SnappedVertex& q = snap[std::size_t(x)];
      return ExactPoint::on_segment(end_a(q), end_b(q), q.s);
    }
    return ExactPoint(V.row(x).transpose());
  }
  std::array<ExactPoint, 3> exact_face(int f) const {
    return {corner(f, 0), corner(f, 1), corner(f, 2)};
  }
  // Moved faces filed in a hash grid by their current boxes (queries near a chain must not scan
  // every moved face).
  double cell = 1;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::unordered_map<std::int64_t, std::vector<int>> grid;
  std::vector<CGAL::Bbox_3> filed_box;  // per face: the box it is filed under
  std::array<std::int64_t, 6> cells_of(const CGAL::Bbox_3& b) const {
    return {std::int64_t(std::floor((b.xmin() - origin.x()) / cell)),
            std::int64_t(std::floor((b.ymin() - origin.y()) / cell)),
            std::int64_t(std::floor((b.zmin() - origin.z()) / cell)),
            std::int64_t(std::floor((b.xmax() - origin.x()) / cell)),
            std::int64_t(std::floor((b.ymax() - origin.y()) / cell)),
            std::int64_t(std::floor((b.zmax() - origin.z()) / cell))};
  }
  static std::int64_t key(std::int64_t i, std::int64_t j, std::int64_t k) {
    return (i & 0x1fffff) | ((j & 0x1fffff) << 21) | ((k & 0x1fffff) << 42);
  }
  template <class Fn>
  void for_cells(const CGAL::Bbox_3& b, Fn&& fn) const {
    const auto c = cells_of(b);
    for (std::int64_t i = c[0]; i <= c[3]; ++i)
      for (std::int64_t j = c[1]; j <= c[4]; ++j)
        for (std::int64_t k = c[2]; k <= c[5]; ++k) fn(key(i, j, k));
  }
  double cell_count(const CGAL::Bbox_3& b) const {
    const auto c = cells_of(b);
    return double(c[3] - c[0] + 1) * double(c[4] - c[1] + 1) * double(c[5] - c[2] + 1);
  }
  void file(int f) {
    filed_box[std::size_t(f)] = face_box(f);
    if (cell_count(filed_box[std::size_t(f)]) > 4096) {
      grid[key(-1, -1, -1) ^ (std::int64_t(1) << 63)].push_back(f);  // too large: kept apart
      return;
    }
    for_cells(filed_box[std::size_t(f)], [&](std::int64_t k) { grid[k].push_back(f); });
  }
  void unfile(int f) {
    auto drop = [&](std::int64_t k) {
      auto it = grid.find(k);
      if (it == grid.end()) return;
      auto& v = it->second;
      v.erase(std::remove(v.begin(), v.end(), f), v.end());
      if (v.empty()) grid.erase(it);
    };
    if (cell_count(filed_box[std::size_t(f)]) > 4096)
      drop(key(-1, -1, -1) ^ (std::int64_t(1) << 63));
    else
      for_cells(filed_box[std::size_t(f)], drop);
  }
  // Moved faces whose current box overlaps b, in increasing order.
  std::vector<int> moved_near(const CGAL::Bbox_3& b) const {
    std::vector<int> out;
    if (moved.empty()) return out;
    if (cell_count(b) > 4096 || cell_count(b) > 4.0 * double(moved.size())) {
      for (int f : moved)
        if (CGAL::do_overlap(b, face_box(f))) out.push_back(f);
    } else {
      auto take = [&](std::int64_t k) {
        if (auto it = grid.find(k); it != grid.end())
          for (int f : it->second)
            if (CGAL::do_overlap(b, face_box(f))) out.push_back(f);
      };
      for_cells(b, take);
      take(key(-1, -1, -1) ^ (std::int64_t(1) << 63));
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  CGAL::Bbox_3 face_box(int f) const {
    if (!is_moved(f)) return boxes[std::size_t(f)];
    CGAL::Bbox_3 out;
    for (int k = 0; k < 3; ++k) {
      const int x = F(f, k);
      if (snap[std::size_t(x)].vertex >= 0)
        out += snap_box[std::size_t(x)];
      else
        out += CGAL::Bbox_3(V(x, 0), V(x, 1), V(x, 2), V(x, 0), V(x, 1), V(x, 2));
    }
    return out;
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

InputSurfaceIndex::InputSurfaceIndex(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                     const std::vector<SnappedVertex>& snaps)
    : InputSurfaceIndex(V, F) {
  for (const SnappedVertex& q : snaps) snap_vertex(q);
}

void InputSurfaceIndex::snap_vertex(const SnappedVertex& q) {
  Impl& m = *m_impl;
  const int nv = int(m.V.rows());
  if (q.vertex < 0 || q.vertex >= nv || q.a < -1 || q.a >= nv || q.b < -1 || q.b >= nv ||
      q.a == q.vertex || q.b == q.vertex || !(q.s > 0 && q.s < 1) ||
      (q.a < 0 && !q.pa.allFinite()) || (q.b < 0 && !q.pb.allFinite()))
    throw std::invalid_argument("InputSurfaceIndex::snap_vertex: bad snap of vertex " +
                                std::to_string(q.vertex) + " onto (" + std::to_string(q.a) + ", " +
                                std::to_string(q.b) + ") at " + std::to_string(q.s) + " (" +
                                std::to_string(nv) + " vertices)");
  if (m.snap.empty()) {
    m.Vref = m.V;
    m.snap.assign(std::size_t(nv), SnappedVertex{});
    m.snap_box.assign(std::size_t(nv), CGAL::Bbox_3());
    m.moved_at.assign(std::size_t(m.F.rows()), -1);
    m.moved_corners.assign(std::size_t(m.F.rows()), 0);
    m.vf.assign(std::size_t(nv), {});
    for (int f = 0; f < m.F.rows(); ++f)
      for (int k = 0; k < 3; ++k) m.vf[std::size_t(m.F(f, k))].push_back(f);
    m.filed_box.assign(std::size_t(m.F.rows()), CGAL::Bbox_3());
    // Grid cells of twice the mean extent of an input triangle's box.
    double extent = 0;
    for (const CGAL::Bbox_3& b : m.boxes)
      extent += std::max({b.xmax() - b.xmin(), b.ymax() - b.ymin(), b.zmax() - b.zmin()});
    m.cell = m.boxes.empty() ? 1.0 : 2 * extent / double(m.boxes.size());
    if (!(m.cell > 0)) m.cell = 1;
    m.origin = m.V.colwise().minCoeff().transpose();
  }
  const bool was = m.snap[std::size_t(q.vertex)].vertex >= 0;
  m.snap[std::size_t(q.vertex)] = q;
  const ExactPoint p = ExactPoint::on_segment(m.end_a(q), m.end_b(q), q.s);
  m.Vref.row(q.vertex) = p.p.transpose();
  {
    CGAL::Protect_FPU_rounding<true> guard;
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      const CGAL::Interval_nt<false> c = coord<CGAL::Interval_nt<false>>(p, k);
      lo[k] = c.inf();
      hi[k] = c.sup();
    }
    m.snap_box[std::size_t(q.vertex)] = CGAL::Bbox_3(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  }
  for (int f : m.vf[std::size_t(q.vertex)]) {
    if (m.moved_corners[std::size_t(f)] > 0) m.unfile(f);  // filed under its old box
    if (!was && m.moved_corners[std::size_t(f)]++ == 0) {
      m.moved_at[std::size_t(f)] = int(m.moved.size());
      m.moved.push_back(f);
    }
    m.file(f);
  }
}

void InputSurfaceIndex::unsnap_vertex(int x) {
  Impl& m = *m_impl;
  if (m.snap.empty() || x < 0 || x >= int(m.V.rows()) || m.snap[std::size_t(x)].vertex < 0) return;
  m.snap[std::size_t(x)] = SnappedVertex{};
  m.Vref.row(x) = m.V.row(x);
  for (int f : m.vf[std::size_t(x)]) {
    m.unfile(f);
    if (--m.moved_corners[std::size_t(f)] == 0) {
      const int at = m.moved_at[std::size_t(f)];
      m.moved[std::size_t(at)] = m.moved.back();
      m.moved_at[std::size_t(m.moved.back())] = at;
      m.moved.pop_back();
      m.moved_at[std::size_t(f)] = -1;
    } else {
      m.file(f);  // still moved, under its new box
    }
  }
}

const SnappedVertex* InputSurfaceIndex::snap_of(int x) const {
  const Impl& m = *m_impl;
  if (m.snap.empty() || x < 0 || x >= int(m.V.rows()) || m.snap[std::size_t(x)].vertex < 0)
    return nullptr;
  return &m.snap[std::size_t(x)];
}

std::vector<SnappedVertex> InputSurfaceIndex::snaps() const {
  std::vector<SnappedVertex> out;
  for (const SnappedVertex& q : m_impl->snap)
    if (q.vertex >= 0) out.push_back(q);
  return out;
}

const Eigen::MatrixXd& InputSurfaceIndex::reference_V() const {
  return m_impl->snap.empty() ? m_impl->V : m_impl->Vref;
}
const std::vector<int>& InputSurfaceIndex::moved_faces() const { return m_impl->moved; }
std::array<ExactPoint, 3> InputSurfaceIndex::exact_face(int f) const {
  return m_impl->exact_face(f);
}

int InputSurfaceIndex::face_normal_dot_sign(int f, const Eigen::Vector3d& from,
                                            const Eigen::Vector3d& to) const {
  if (m_impl->is_moved(f)) return exact_normal_dot_sign(m_impl->exact_face(f), from, to);
  return normal_dot_sign(face_triangle(f), from, to);
}

bool InputSurfaceIndex::face_degenerate(int f) const {
  return exact_collinear(m_impl->exact_face(f));
}

double InputSurfaceIndex::face_area_ratio(int f) const {
  const auto r = face_triangle(f);
  const Eigen::MatrixXd& V = m_impl->V;
  const Eigen::Vector3d a = V.row(m_impl->F(f, 0)), b = V.row(m_impl->F(f, 1)),
                        c = V.row(m_impl->F(f, 2));
  const double input = (b - a).cross(c - a).norm();
  if (!(input > 0)) return 1;
  return (r[1] - r[0]).cross(r[2] - r[0]).norm() / input;
}

namespace {
// Does the closed segment [p, q] meet the closed triangle t (exact; a segment in t's plane
// counts as meeting, conservatively)?
bool segment_meets_triangle(const ExactPoint& p, const ExactPoint& q,
                            const std::array<ExactPoint, 3>& t) {
  const int sp = sdet(t[1], t[0], t[2], t[0], p, t[0]), sq = sdet(t[1], t[0], t[2], t[0], q, t[0]);
  if (sp == 0 && sq == 0) return true;
  if (sp * sq > 0) return false;
  // The line p→q crosses the plane inside the closed triangle iff the three signs of the edge
  // orientations agree (zeros allowed).
  int pos = 0, neg = 0;
  for (int k = 0; k < 3; ++k) {
    const int s = sdet(q, p, t[k], p, t[(k + 1) % 3], p);
    pos += s > 0;
    neg += s < 0;
  }
  return pos == 0 || neg == 0;
}
}  // namespace

namespace {
// Coplanar closed triangles, in the first projection that keeps a non-degenerate: separated iff
// an edge line of one has the other strictly outside.
bool coplanar_triangles_meet(const std::array<ExactPoint, 3>& a,
                             const std::array<ExactPoint, 3>& b) {
  for (int drop : {2, 0, 1}) {
    if (orient2(drop, a[0], a[1], a[2]) == 0) continue;
    for (int side = 0; side < 2; ++side) {
      const auto& x = side ? b : a;
      const auto& y = side ? a : b;
      for (int k = 0; k < 3; ++k) {
        const int inner = orient2(drop, x[k], x[(k + 1) % 3], x[(k + 2) % 3]);
        if (inner == 0) break;
        bool outside = true;
        for (const auto& q : y)
          outside = outside && orient2(drop, x[k], x[(k + 1) % 3], q) == -inner;
        if (outside) return false;
      }
    }
    return true;
  }
  return true;  // degenerate in every projection (conservative)
}
// Is point d in the closed cone at p spanned by u and v (a proper triangle's corner), in the
// projection dropping `drop`?
bool in_closed_cone(int drop, const ExactPoint& p, const ExactPoint& u, const ExactPoint& v,
                    const ExactPoint& d) {
  const int o = orient2(drop, p, u, v);
  return o * orient2(drop, p, u, d) >= 0 && o * orient2(drop, p, d, v) >= 0;
}
}  // namespace

bool InputSurfaceIndex::face_self_intersects(int g) const {
  const Impl& m = *m_impl;
  const auto a = m.exact_face(g);
  const CGAL::Bbox_3 box = m.face_box(g);
  for (int h : faces_in_box(Eigen::Vector3d(box.xmin(), box.ymin(), box.zmin()),
                            Eigen::Vector3d(box.xmax(), box.ymax(), box.zmax()))) {
    if (h == g || !CGAL::do_overlap(box, m.face_box(h))) continue;
    const auto b = m.exact_face(h);
    int shared = 0, ka = -1, kb = -1;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (m.F(g, i) == m.F(h, j)) {
          ++shared;
          ka = i;
          kb = j;
        }
    if (shared == 0) {
      // Closed triangles: the separating planes of triangles_meet_closed, both sides exact.
      bool apart = false;
      for (int side = 0; side < 2 && !apart; ++side) {
        const auto& x = side ? b : a;
        const auto& y = side ? a : b;
        int pos = 0, neg = 0;
        for (const auto& q : y) {
          const int sg = sdet(x[1], x[0], x[2], x[0], q, x[0]);
          pos += sg > 0;
          neg += sg < 0;
        }
        apart = pos == 3 || neg == 3;
        if (side == 0 && pos == 0 && neg == 0) {  // coplanar
          if (coplanar_triangles_meet(a, b)) return true;
          apart = true;
        }
      }
      for (int i = 0; i < 3 && !apart; ++i)
        for (int j = 0; j < 3 && !apart; ++j) {
          const ExactPoint &p0 = a[i], &p1 = a[(i + 1) % 3], &p2 = a[(i + 2) % 3];
          const ExactPoint &q0 = b[j], &q1 = b[(j + 1) % 3], &q2 = b[(j + 2) % 3];
          const int sa = sdet(p1, p0, q1, q0, p2, p0);
          const int s0 = sdet(p1, p0, q1, q0, q0, p0), s2 = sdet(p1, p0, q1, q0, q2, p0);
          if (s0 == 0 || s0 != s2) continue;
          apart = sa == 0 || sa == -s0;
        }
      if (!apart) return true;
    } else if (shared == 1) {
      // Only the common corner: neither opposite edge may meet the other triangle; coplanar
      // triangles sharing a corner count as meeting.
      bool coplanar = true;
      for (const auto& q : b) coplanar = coplanar && sdet(a[1], a[0], a[2], a[0], q, a[0]) == 0;
      if (!coplanar) {
        if (segment_meets_triangle(a[(ka + 1) % 3], a[(ka + 2) % 3], b) ||
            segment_meets_triangle(b[(kb + 1) % 3], b[(kb + 2) % 3], a))
          return true;
        continue;
      }
      // Coplanar: their corners' closed cones at the common corner meet beyond it iff a
      // boundary ray of one lies in the other.
      const ExactPoint& p = a[ka];
      const ExactPoint &a1 = a[(ka + 1) % 3], &a2 = a[(ka + 2) % 3];
      const ExactPoint &b1 = b[(kb + 1) % 3], &b2 = b[(kb + 2) % 3];
      int drop = 0;
      while (drop < 3 && orient2(drop, p, a1, a2) == 0) ++drop;
      if (drop == 3 || orient2(drop, p, b1, b2) == 0) return true;  // degenerate (conservative)
      if (in_closed_cone(drop, p, a1, a2, b1) || in_closed_cone(drop, p, a1, a2, b2) ||
          in_closed_cone(drop, p, b1, b2, a1) || in_closed_cone(drop, p, b1, b2, a2))
        return true;
    } else if (shared == 2) {
      // A common edge: they overlap only if coplanar with both far corners on one side of it.
      int c = 0, d = 0;
      for (int i = 0; i < 3; ++i) {
        bool in_h = false;
        for (int j = 0; j < 3; ++j) in_h = in_h || m.F(g, i) == m.F(h, j);
        if (!in_h) c = i;
      }
      for (int j = 0; j < 3; ++j) {
        bool in_g = false;
        for (int i = 0; i < 3; ++i) in_g = in_g || m.F(g, i) == m.F(h, j);
        if (!in_g) d = j;
      }
      const ExactPoint &e0 = a[(c + 1) % 3], &e1 = a[(c + 2) % 3];
      if (sdet(e1, e0, a[c], e0, b[d], e0) != 0) continue;
      for (int drop = 0; drop < 3; ++drop) {
        const int sc = orient2(drop, e0, e1, a[c]), sd = orient2(drop, e0, e1, b[d]);
        if (sc == 0 && sd == 0) continue;  // this projection flattens the plane
        if (sc * sd >= 0) return true;
        break;
      }
    } else {
      return true;  // a duplicate face
    }
  }
  return false;
}

InputSurfaceIndex::~InputSurfaceIndex() = default;
const Eigen::MatrixXd& InputSurfaceIndex::V() const { return m_impl->V; }
const Eigen::MatrixXi& InputSurfaceIndex::F() const { return m_impl->F; }

namespace {

// Distance along the unit `d` from `o` to the triangle, the ray lying in the triangle's plane
// and meeting it (both decided exactly by the caller): 0 when o is in the triangle, else the
// nearest crossing of the ray with an edge.
double coplanar_ray_distance(const Triangle& tri, const V3& o, const V3& d) {
  if (tri.has_on(pt(o))) return 0.0;
  const V3 c[3] = {V3(tri[0].x(), tri[0].y(), tri[0].z()), V3(tri[1].x(), tri[1].y(), tri[1].z()),
                   V3(tri[2].x(), tri[2].y(), tri[2].z())};
  const V3 n = (c[1] - c[0]).cross(c[2] - c[0]).normalized();
  double best = std::numeric_limits<double>::infinity();
  // An edge along the ray (parallel, den = 0) is skipped: where it lies on the ray, its ends are
  // crossings of the two other edges.
  for (int k = 0; k < 3; ++k) {
    const V3 p = c[k], e = c[(k + 1) % 3] - c[k], w = p - o;
    const double den = d.cross(e).dot(n);
    if (!(std::abs(den) > 1e-12 * e.norm())) continue;
    const double t = w.cross(e).dot(n) / den, u = w.cross(d).dot(n) / den;
    if (u >= -1e-12 && u <= 1 + 1e-12) best = std::min(best, std::max(t, 0.0));
  }
  if (std::isfinite(best)) return best;
  // Rounding missed every edge though the exact test found contact: a lower bound (the distance
  // along d is linear on the triangle, smallest at a corner).
  for (const V3& x : c) best = std::min(best, std::max((x - o).dot(d), 0.0));
  return best;
}

}  // namespace

double InputSurfaceIndex::ray_distance(const Eigen::Vector3d& origin,
                                       const Eigen::Vector3d& direction,
                                       const std::vector<int>& ignore,
                                       const std::vector<int>* among) const {
  const K::Ray_3 ray(pt(origin), K::Vector_3(direction.x(), direction.y(), direction.z()));
  // CGAL 5.5's ray/triangle intersection is wrong for a ray in the triangle's plane: a ray
  // pointing away from a coplanar triangle (do_intersect false) got the segment from its own
  // source to a triangle corner, hence distance 0 — on CAD inputs, whose rays often lie in the
  // plane of a distant face, a zero shell step ("cannot be made positive") or thickness. Coplanar
  // faces are therefore skipped in the traversal and measured here; every face the traversal
  // prunes is farther than its answer, so the smaller of the two is the first hit.
  const Point second = ray.second_point();
  const V3 unit_direction = direction.normalized();
  double coplanar = std::numeric_limits<double>::infinity();
  auto skip = [&](const std::vector<Triangle>::const_iterator& it) {
    if (std::find(ignore.begin(), ignore.end(), m_impl->id(it)) != ignore.end()) return true;
    if (among && !std::binary_search(among->begin(), among->end(), m_impl->id(it))) return true;
    const Triangle& tri = *it;
    if (CGAL::orientation(tri[0], tri[1], tri[2], ray.source()) != CGAL::COPLANAR ||
        CGAL::orientation(tri[0], tri[1], tri[2], second) != CGAL::COPLANAR)
      return false;
    if (!tri.is_degenerate() && CGAL::do_intersect(tri, ray))
      coplanar = std::min(coplanar, coplanar_ray_distance(tri, origin, unit_direction));
    return true;
  };
  const auto hit = m_impl->tree.first_intersection(ray, skip);
  double found = std::numeric_limits<double>::infinity();
  if (hit) {
    if (const Point* p = boost::get<Point>(&hit->first))
      found = std::sqrt(CGAL::to_double(CGAL::squared_distance(*p, ray.source())));
    else if (const Segment* s = boost::get<Segment>(&hit->first))
      found =
          std::sqrt(std::min(CGAL::to_double(CGAL::squared_distance(s->source(), ray.source())),
                             CGAL::to_double(CGAL::squared_distance(s->target(), ray.source()))));
    else
      found = 0.0;
  }
  return std::min(found, coplanar);
}

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
                                            const Eigen::Vector3i& corner_ids,
                                            const std::vector<int>* among) const {
  const Triangle tri(pt(c[0]), pt(c[1]), pt(c[2]));
  if (tri.is_degenerate()) return true;  // never accept a flat base/top triangle
  // Faces whose box overlaps the triangle's, then the exact test on each (the tree's own
  // triangle query tests every node box against the triangle exactly, which costs more than it
  // prunes here).
  std::vector<int> candidates;
  BoxOverlapTraits traits{&m_impl->triangles, &m_impl->boxes, &candidates};
  m_impl->tree.traversal(tri.bbox(), traits);
  auto counts = [among](int f) {
    return !among || std::binary_search(among->begin(), among->end(), f);
  };
  for (int f : candidates) {
    if (m_impl->is_moved(f) || !counts(f)) continue;  // moved: below
    if (face_contact(c, singular, corner_ids, f, false)) return true;
  }
  // Moved faces of the reference copy, exactly.
  for (int f : m_impl->moved_near(tri.bbox()))
    if (counts(f) && face_contact(c, singular, corner_ids, f, false)) return true;
  return false;
}

bool InputSurfaceIndex::triangle_meets_face(const std::array<Eigen::Vector3d, 3>& c,
                                            const std::array<bool, 3>& singular,
                                            const Eigen::Vector3i& corner_ids, int f) const {
  if (Triangle(pt(c[0]), pt(c[1]), pt(c[2])).is_degenerate()) return true;
  return face_contact(c, singular, corner_ids, f, false);
}

bool InputSurfaceIndex::face_contact(const std::array<Eigen::Vector3d, 3>& c,
                                     const std::array<bool, 3>& singular,
                                     const Eigen::Vector3i& corner_ids, int f,
                                     bool known_to_meet) const {
  int pinch = -1, shared = -1;  // c's corner at a singular input vertex of face f
  for (int k = 0; k < 3; ++k)
    if (singular[k])
      for (int j = 0; j < 3; ++j)
        if (m_impl->F(f, j) == corner_ids[k]) {
          pinch = k;
          shared = j;
        }
  if (m_impl->is_moved(f))  // conservative: no exact pinch test for snapped corners
    return pinch >= 0 || exact_triangles_meet(m_impl->exact_face(f), c);
  if (!known_to_meet && !CGAL::do_intersect(Triangle(pt(c[0]), pt(c[1]), pt(c[2])),
                                            m_impl->triangles[std::size_t(f)]))
    return false;
  return pinch < 0 || triangles_meet_beyond_pinch(c, pinch, face_triangle(f), shared);
}

namespace {
// The orientation of point p against a fixed plane through a, b, c, many times: the cross
// product and the absolute cofactors are computed once, each query is a dot product with a
// semi-static error bound (Shewchuk's orient3d bound A, (7 + 56 eps) eps times the permanent,
// taken with a margin), and CGAL's exact predicate decides where the bound does not.
struct PlaneSide {
  Point a, b, c;
  V3 o, n, cof;
  explicit PlaneSide(const Point& pa, const Point& pb, const Point& pc) : a(pa), b(pb), c(pc) {
    o = V3(pa.x(), pa.y(), pa.z());
    const V3 u = V3(pb.x(), pb.y(), pb.z()) - o, v = V3(pc.x(), pc.y(), pc.z()) - o;
    n = u.cross(v);
    cof = V3(std::abs(u.y() * v.z()) + std::abs(u.z() * v.y()),
             std::abs(u.z() * v.x()) + std::abs(u.x() * v.z()),
             std::abs(u.x() * v.y()) + std::abs(u.y() * v.x()));
  }
  // CGAL::orientation(a, b, c, p).
  CGAL::Orientation side(const Point& p) const {
    const V3 w = V3(p.x(), p.y(), p.z()) - o;
    const double det = w.dot(n);
    const double permanent = w.cwiseAbs().dot(cof);
    constexpr double k_bound = 2e-15;  // > (7 + 56 eps) eps = 7.8e-16
    if (det > k_bound * permanent) return CGAL::POSITIVE;
    if (-det > k_bound * permanent) return CGAL::NEGATIVE;
    return CGAL::orientation(a, b, c, p);
  }
};

// The separating-plane test below with the tet's facet planes and sides prepared once per tet.
struct PreparedTet {
  const K::Tetrahedron_3* tet;
  std::array<std::optional<PlaneSide>, 4> facet;  // empty where the facet is flat with tet[j]
  std::array<CGAL::Orientation, 4> inside{};
  explicit PreparedTet(const K::Tetrahedron_3& t) : tet(&t) {
    static constexpr int f[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    for (int j = 0; j < 4; ++j) {
      inside[std::size_t(j)] = CGAL::orientation(t[f[j][0]], t[f[j][1]], t[f[j][2]], t[j]);
      if (inside[std::size_t(j)] != CGAL::COPLANAR)
        facet[std::size_t(j)].emplace(t[f[j][0]], t[f[j][1]], t[f[j][2]]);
    }
  }
  // strictly_separated(tri, *tet), below; `plane` is tri's.
  bool separated(const Triangle& tri, const PlaneSide& plane) const {
    for (std::size_t j = 0; j < 4; ++j) {
      if (!facet[j]) continue;
      bool all_out = true;
      for (int k = 0; k < 3 && all_out; ++k) all_out = facet[j]->side(tri[k]) == -inside[j];
      if (all_out) return true;
    }
    const auto s0 = plane.side((*tet)[0]);
    if (s0 == CGAL::COPLANAR) return false;
    for (int j = 1; j < 4; ++j)
      if (plane.side((*tet)[j]) != s0) return false;
    return true;
  }
};

// True if a plane strictly separates the closed triangle from the closed tet: one of the tet's
// facet planes with all three triangle corners strictly outside, or the triangle's plane with
// all four tet corners strictly on one side. Exact (filtered orientation predicates); a cheap
// rejection before CGAL's general triangle-tetrahedron test, which most bounding-box candidates
// would otherwise pay for in interval arithmetic.
bool strictly_separated(const Triangle& tri, const K::Tetrahedron_3& tet) {
  return PreparedTet(tet).separated(tri, PlaneSide(tri[0], tri[1], tri[2]));
}
}  // namespace

std::vector<int> InputSurfaceIndex::faces_touching_tets(
    const std::vector<std::array<Eigen::Vector3d, 4>>& tets, const std::vector<int>& known) const {
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
  // Faces of the reference copy with a snapped corner: exact tests on their exact corners. A
  // corner inside one of the tets is looked for first, in all of them (most such faces lie in
  // the prism), before the complete test tet by tet.
  const std::vector<int> moved = m_impl->moved_near(all);
  std::vector<std::array<int, 4>> sides;
  if (!moved.empty()) {
    sides.reserve(tets.size());
    for (const auto& t : tets) sides.push_back(tet_sides(t));
  }
  for (int f : moved) {
    const CGAL::Bbox_3 fb = m_impl->face_box(f);
    const auto tri = m_impl->exact_face(f);
    bool meets = false;
    for (std::size_t i = 0; i < T.size() && !meets; ++i)
      meets = CGAL::do_overlap(fb, tb[i]) && corner_in_closed_tet(tri, tets[i], sides[i]);
    for (std::size_t i = 0; i < T.size() && !meets; ++i)
      meets = CGAL::do_overlap(fb, tb[i]) && meets_tet<true>(tri, tets[i]);
    if (meets) out.push_back(f);
  }
  for (int f : known)
    if (!m_impl->is_moved(f)) out.push_back(f);
  std::vector<PreparedTet> prepared;
  prepared.reserve(T.size());
  for (const auto& t : T) prepared.emplace_back(t);
  for (int f : candidates) {
    if (m_impl->is_moved(f)) continue;                                // above
    if (std::binary_search(known.begin(), known.end(), f)) continue;  // reported above
    const Triangle& tri = m_impl->triangles[std::size_t(f)];
    const CGAL::Bbox_3& fb = m_impl->boxes[std::size_t(f)];
    std::optional<PlaneSide> plane;
    for (std::size_t i = 0; i < T.size(); ++i) {
      if (!CGAL::do_overlap(fb, tb[i])) continue;
      // A triangle corner that IS a tet corner touches the closed tet: decided without the exact
      // fallback CGAL's filtered predicate takes for such degenerate contacts (the shell's middle
      // surface starts on the input vertices, so they are the common case).
      bool shared = false;
      for (int a = 0; a < 3 && !shared; ++a)
        for (int j = 0; j < 4 && !shared; ++j) shared = tri.vertex(a) == T[i].vertex(j);
      if (!shared && !plane) plane.emplace(tri[0], tri[1], tri[2]);
      if (shared || (!prepared[i].separated(tri, *plane) && CGAL::do_intersect(tri, T[i]))) {
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
  if (!m_impl->moved.empty()) {
    for (int f : m_impl->moved_near(box)) out.push_back(f);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  return out;
}

std::vector<int> InputSurfaceIndex::faces_containing(const Eigen::Vector3d& p,
                                                     const std::vector<int>* among) const {
  std::vector<int> out;
  const Eigen::MatrixXd& V = reference_V();
  for (int f : faces_in_box(p, p)) {
    if (among && !std::binary_search(among->begin(), among->end(), f)) continue;
    const auto r = face_triangle(f);  // rounded where moved
    const Triangle t(pt(r[0]), pt(r[1]), pt(r[2]));
    if (t.is_degenerate()) continue;
    bool corner = false;
    for (int k = 0; k < 3; ++k) corner |= V.row(m_impl->F(f, k)) == p.transpose();
    if (corner || t.has_on(pt(p))) out.push_back(f);
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool InputSurfaceIndex::face_touches_tet(int f, const std::array<Eigen::Vector3d, 4>& t) const {
  if (m_impl->is_moved(f)) return exact_triangle_meets_tet(m_impl->exact_face(f), t);
  const K::Tetrahedron_3 tet(pt(t[0]), pt(t[1]), pt(t[2]), pt(t[3]));
  const Triangle& tri = m_impl->triangles[std::size_t(f)];
  return !strictly_separated(tri, tet) && CGAL::do_intersect(tri, tet);
}

bool InputSurfaceIndex::face_section_contact(int f, const std::array<Eigen::Vector3d, 4>& t) const {
  if (m_impl->is_moved(f)) return exact_section_contact(m_impl->exact_face(f), t);
  return triangle_section_contact(face_triangle(f), t);
}

std::array<Eigen::Vector3d, 3> InputSurfaceIndex::face_triangle(int f) const {
  const Eigen::MatrixXd& V = m_impl->snap.empty() ? m_impl->V : m_impl->Vref;
  return {V.row(m_impl->F(f, 0)).transpose(), V.row(m_impl->F(f, 1)).transpose(),
          V.row(m_impl->F(f, 2)).transpose()};
}

int InputSurfaceIndex::closest_face(const Eigen::Vector3d& p, Eigen::Vector3d& closest) const {
  const auto [q, it] = m_impl->tree.closest_point_and_primitive(pt(p));
  closest = Eigen::Vector3d(q.x(), q.y(), q.z());
  return m_impl->id(it);
}

int InputSurfaceIndex::segment_hit(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   Eigen::Vector3d& bary, const std::vector<int>* among) const {
  // A zero-length segment (consecutive fiber corners can coincide) crosses nothing; CGAL's
  // segment tests assume a proper segment.
  if (a == b) return -1;
  const Segment seg(pt(a), pt(b));
  std::vector<std::vector<Triangle>::const_iterator> hits;
  m_impl->tree.all_intersected_primitives(seg, std::back_inserter(hits));
  std::vector<int> candidates;
  for (const auto& it : hits)
    if (!m_impl->is_moved(m_impl->id(it))) candidates.push_back(m_impl->id(it));
  if (among)
    candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                    [among](int f) {
                                      return !std::binary_search(among->begin(), among->end(), f);
                                    }),
                     candidates.end());
  // Moved faces of the reference copy as their rounded triangles (shared corners keep the
  // rounded copy watertight, so a segment crossing near a chain hits one side or the other).
  for (int f : m_impl->moved_near(seg.bbox())) {
    if (among && !std::binary_search(among->begin(), among->end(), f)) continue;
    const auto t = face_triangle(f);
    if (CGAL::do_intersect(seg, Triangle(pt(t[0]), pt(t[1]), pt(t[2])))) candidates.push_back(f);
  }
  int best = -1;
  double best_t = std::numeric_limits<double>::infinity();
  for (const int f : candidates) {
    const auto tri = face_triangle(f);
    const Eigen::Vector3d p0 = tri[0], p1 = tri[1], p2 = tri[2];
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
