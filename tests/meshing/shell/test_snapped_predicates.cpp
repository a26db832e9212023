// Exact predicates on the reference copy of the input, whose snapped vertices stand for the exact
// points a + s (b − a): agreement with CGAL (Epick) for plain doubles and with an exact rational
// reference for snapped points on small integer grids, snapped points decided exactly where their
// roundings are not, and the snapped ("moved") faces of InputSurfaceIndex.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include "meshing/shell/shell_intersection.hpp"

namespace sh = curvefem::meshing::shell;
using Eigen::Vector3d;

namespace {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using Q = CGAL::Exact_rational;
using Exact = CGAL::Simple_cartesian<Q>;
using EP = Exact::Point_3;
using EV = Exact::Vector_3;

using Tri = std::array<Vector3d, 3>;
using Tet = std::array<Vector3d, 4>;
using ExactTri = std::array<sh::ExactPoint, 3>;

Epick::Point_3 inexact(const Vector3d& p) { return Epick::Point_3(p.x(), p.y(), p.z()); }
Epick::Triangle_3 inexact(const Tri& t) {
  return Epick::Triangle_3(inexact(t[0]), inexact(t[1]), inexact(t[2]));
}
Epick::Tetrahedron_3 inexact(const Tet& t) {
  return Epick::Tetrahedron_3(inexact(t[0]), inexact(t[1]), inexact(t[2]), inexact(t[3]));
}

// The exact rational point an ExactPoint stands for.
EP exact(const sh::ExactPoint& p) {
  if (!p.snapped) return EP(Q(p.p.x()), Q(p.p.y()), Q(p.p.z()));
  Q c[3];
  for (int k = 0; k < 3; ++k) c[k] = Q(p.a[k]) + Q(p.s) * (Q(p.b[k]) - Q(p.a[k]));
  return EP(c[0], c[1], c[2]);
}
EP exact(const Vector3d& p) { return exact(sh::ExactPoint(p)); }
std::array<EP, 3> exact(const ExactTri& t) { return {exact(t[0]), exact(t[1]), exact(t[2])}; }
std::array<EP, 4> exact(const Tet& t) {
  return {exact(t[0]), exact(t[1]), exact(t[2]), exact(t[3])};
}

Q det3(const EV& u, const EV& v, const EV& w) {
  return Q(u.x() * (v.y() * w.z() - v.z() * w.y()) - u.y() * (v.x() * w.z() - v.z() * w.x()) +
           u.z() * (v.x() * w.y() - v.y() * w.x()));
}
int sign(const Q& q) { return q > 0 ? 1 : (q < 0 ? -1 : 0); }

ExactTri plain(const Tri& t) { return {t[0], t[1], t[2]}; }
Tri rounded(const ExactTri& t) { return {t[0].p, t[1].p, t[2].p}; }

// Exact reference for a (possibly degenerate) closed triangle against a non-degenerate tet: clip
// the triangle by the 4 closed facet half-spaces (Sutherland–Hodgman, exact rationals) into the
// convex set C. The closed sets meet iff C ≠ ∅. A positive combination of C's vertices lies on a
// facet plane iff all of them do, so C meets the open tet iff C is not contained in one facet
// plane, and a triangle lying in the plane of facet j meets that facet's relative interior iff C
// is contained in none of the other 3 facet planes.
struct Reference {
  bool closed = false, section = false;
};
constexpr int k_facet[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};

Reference reference(const std::array<EP, 3>& t, const std::array<EP, 4>& T) {
  auto value = [&](int j, const EP& p) {  // ≥ 0 on the tet's side of facet plane j
    const EP &a = T[k_facet[j][0]], &b = T[k_facet[j][1]], &c = T[k_facet[j][2]];
    const Q inside = det3(b - a, c - a, T[k_facet[j][3]] - a);
    const Q v = det3(b - a, c - a, p - a);
    return inside > 0 ? v : Q(-v);
  };
  std::vector<EP> poly(t.begin(), t.end());
  for (int j = 0; j < 4 && !poly.empty(); ++j) {
    std::vector<EP> out;
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const EP &p = poly[i], &q = poly[(i + 1) % poly.size()];
      const Q fp = value(j, p), fq = value(j, q);
      if (fp >= 0) out.push_back(p);
      if ((fp > 0 && fq < 0) || (fp < 0 && fq > 0)) out.push_back(p + (q - p) * Q(fp / (fp - fq)));
    }
    poly = std::move(out);
  }
  Reference r;
  if (poly.empty()) return r;
  r.closed = true;
  bool on[4];
  for (int j = 0; j < 4; ++j) {
    on[j] = true;
    for (const EP& p : poly) on[j] = on[j] && value(j, p) == 0;
  }
  r.section = !on[0] && !on[1] && !on[2] && !on[3];
  for (int j = 0; j < 4; ++j) {
    const bool coplanar = value(j, t[0]) == 0 && value(j, t[1]) == 0 && value(j, t[2]) == 0;
    bool relint = coplanar;
    for (int k = 0; k < 4; ++k) relint = relint && (k == j || !on[k]);
    r.section = r.section || relint;
  }
  return r;
}

bool degenerate(const std::array<EP, 3>& t) { return CGAL::collinear(t[0], t[1], t[2]); }
bool coplanar(const std::array<EP, 3>& a, const std::array<EP, 3>& b) {
  for (const EP& q : b)
    if (!CGAL::coplanar(a[0], a[1], a[2], q)) return false;
  return true;
}

// Sign of ((t1 − t0) × (t2 − t0)) · (to − from), exactly.
int normal_dot_sign_exact(const std::array<EP, 3>& t, const EP& from, const EP& to) {
  return sign(det3(t[1] - t[0], t[2] - t[0], to - from));
}

bool non_degenerate(const Tet& t) {
  return (t[1] - t[0]).cross(t[2] - t[0]).dot(t[3] - t[0]) != 0;  // exact on small integers
}

// exact_triangles_meet(t, u) against exact rationals: a coplanar pair must count as meeting
// (conservative), any other pair as CGAL decides exactly. Counts the outcomes.
struct PairCounts {
  int meet = 0, miss = 0, coplanar = 0;
};
::testing::AssertionResult triangles_meet_as_reference(const ExactTri& t, const Tri& u,
                                                       PairCounts& n) {
  const std::array<EP, 3> et = exact(t), eu = exact(plain(u));
  const bool ours = sh::exact_triangles_meet(t, u);
  if (coplanar(et, eu)) {
    ++n.coplanar;
    if (ours) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "a coplanar pair does not meet";
  }
  const bool cgal = CGAL::do_intersect(Exact::Triangle_3(et[0], et[1], et[2]),
                                       Exact::Triangle_3(eu[0], eu[1], eu[2]));
  n.meet += cgal;
  n.miss += !cgal;
  if (ours == cgal) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "meets " << ours << ", exactly " << cgal;
}

}  // namespace

// ---------------------------------------------------------------- plain doubles against CGAL

TEST(SnappedPredicates, UnsnappedPointsMatchCgalOnIntegerGrids) {
  std::mt19937 rng(2024);
  std::uniform_int_distribution<int> coord(0, 4), pick4(0, 3), coin(0, 3);
  auto grid = [&] { return Vector3d(coord(rng), coord(rng), coord(rng)); };
  int meets = 0, misses = 0, section = 0, touch_only = 0, tri_meet = 0, tri_miss = 0,
      tri_coplanar = 0;
  for (int trial = 0; trial < 6000; ++trial) {
    Tet T;
    do T = {grid(), grid(), grid(), grid()};
    while (!non_degenerate(T));
    // Corners shared with the tet make the degenerate contacts (vertex, edge, facet) frequent.
    auto corner = [&] { return coin(rng) == 0 ? T[pick4(rng)] : grid(); };
    Tri t;
    do t = {corner(), corner(), corner()};
    while ((t[1] - t[0]).cross(t[2] - t[0]).squaredNorm() == 0);
    const bool cgal = CGAL::do_intersect(inexact(t), inexact(T));
    ASSERT_EQ(sh::exact_triangle_meets_tet(plain(t), T), cgal) << "trial " << trial;
    const bool contact = sh::triangle_section_contact(t, T);
    ASSERT_EQ(sh::exact_section_contact(plain(t), T), contact) << "trial " << trial;
    ASSERT_TRUE(!contact || cgal) << "trial " << trial;  // section contact is contact
    meets += cgal;
    misses += !cgal;
    section += contact;
    touch_only += cgal && !contact;

    // Triangle pairs: the second one often a facet of the tet or sharing a corner with t.
    Tri u;
    do {
      const int mode = pick4(rng);
      if (mode == 0) {
        const int j = pick4(rng);
        u = {T[k_facet[j][0]], T[k_facet[j][1]], T[k_facet[j][2]]};
      } else if (mode == 1 && coin(rng) == 0) {  // in t's plane (affine combinations of t)
        u = coin(rng) < 2 ? Tri{t[0] + t[1] - t[2], t[1] + t[2] - t[0], t[2] + t[0] - t[1]}
                          : Tri{2 * t[0] - t[1], 2 * t[0] - t[2], 3 * t[0] - t[1] - t[2]};
      } else {
        u = {coin(rng) == 0 ? t[pick4(rng) % 3] : grid(), grid(), grid()};
      }
    } while ((u[1] - u[0]).cross(u[2] - u[0]).squaredNorm() == 0);
    const bool ours = sh::exact_triangles_meet(plain(t), u);
    const Epick::Triangle_3 ct = inexact(t), cu = inexact(u);
    if (CGAL::coplanar(ct[0], ct[1], ct[2], cu[0]) && CGAL::coplanar(ct[0], ct[1], ct[2], cu[1]) &&
        CGAL::coplanar(ct[0], ct[1], ct[2], cu[2])) {
      ASSERT_TRUE(ours) << "coplanar pair, trial " << trial;  // conservative by contract
      ++tri_coplanar;
      continue;
    }
    const bool ref = CGAL::do_intersect(ct, cu);
    ASSERT_EQ(ours, ref) << "trial " << trial;
    tri_meet += ref;
    tri_miss += !ref;
  }
  // Every outcome occurs often enough for the comparison to mean something.
  EXPECT_GT(meets, 2000);
  EXPECT_GT(misses, 600);
  EXPECT_GT(section, 1000);
  EXPECT_GT(touch_only, 1000);
  EXPECT_GT(tri_meet, 1500);
  EXPECT_GT(tri_miss, 1200);
  EXPECT_GT(tri_coplanar, 200);
}

// ---------------------------------------------------------------- snapped points, exactly

TEST(SnappedPredicates, SnappedPointsMatchExactRationalReference) {
  std::mt19937 rng(77);
  std::uniform_int_distribution<int> coord(0, 4), pick4(0, 3), pick6(0, 5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Most trials on the integer grid (exact degeneracies); every 4th mapped to non-integer, tiny or
  // huge coordinates (x ↦ scale x + shift, rounded), where the filters fail differently.
  const std::array<std::pair<double, double>, 4> maps = {
      {{1.0, 0.0}, {0.1, 0.37}, {1e-150, 0.0}, {3e100, -1e100}}};
  std::pair<double, double> map = maps[0];
  auto grid = [&] {
    const Vector3d p(coord(rng), coord(rng), coord(rng));
    return Vector3d((map.first * p).array() + map.second);
  };
  // s: not representable steps (the snapped point is not a double) and a few dyadic ones.
  const std::array<double, 9> s_list = {1.0 / 3, 2.0 / 3, 0.1,  0.7, 1.0 / 7,
                                        0.999,   0.5,     0.25, 0.75};
  auto pick_s = [&] {
    const int i = pick6(rng);
    return i == 0 ? std::max(unit(rng), 1e-9) : s_list[std::size_t(rng() % s_list.size())];
  };
  int closed = 0, open = 0, section = 0, touch_only = 0, degen = 0, degen_closed = 0,
      rounding_matters = 0, dyadic = 0;
  PairCounts pairs;
  for (int trial = 0; trial < 2000; ++trial) {
    map = trial % 4 == 0 ? maps[std::size_t(1 + (trial / 4) % 3)] : maps[0];
    Tet T;
    do T = {grid(), grid(), grid(), grid()};
    while (CGAL::orientation(exact(T[0]), exact(T[1]), exact(T[2]), exact(T[3])) == 0);
    // A point in the plane of facet (i, j, k) (exactly so on the integer grid), often outside it.
    auto in_facet_plane = [&] {
      const int j = pick4(rng);
      const int* f = k_facet[j];
      return Vector3d(T[f[0]] + T[f[1]] - T[f[2]]);
    };
    auto snapped = [&] {
      Vector3d u, v;
      do {
        switch (pick4(rng)) {
          case 0: {  // on a tet edge
            const int i = pick4(rng);
            u = T[i];
            v = T[(i + 1 + pick4(rng) % 3) % 4];
            break;
          }
          case 1:  // in a facet plane
            u = T[pick4(rng)];
            v = in_facet_plane();
            break;
          case 2:
            u = T[pick4(rng)];
            v = grid();
            break;
          default:
            u = grid();
            v = grid();
        }
      } while (u == v);
      return sh::ExactPoint::on_segment(u, v, pick_s());
    };
    auto corner = [&]() -> sh::ExactPoint {
      switch (pick6(rng)) {
        case 0:
        case 1:
        case 2:
          return snapped();
        case 3:
          return Vector3d(T[pick4(rng)]);
        case 4:
          return in_facet_plane();
        default:
          return grid();
      }
    };
    ExactTri t = {snapped(), corner(), corner()};
    std::swap(t[0], t[std::size_t(rng() % 3)]);
    const std::array<EP, 3> et = exact(t);
    const std::array<EP, 4> eT = exact(T);
    const Reference ref = reference(et, eT);
    const bool is_degenerate = degenerate(et);
    ASSERT_EQ(sh::exact_collinear(t), is_degenerate) << "trial " << trial;
    const bool meets = sh::exact_triangle_meets_tet(t, T);
    if (!is_degenerate) {
      // The clipping reference agrees with CGAL's exact triangle–tetrahedron test.
      const bool cgal = CGAL::do_intersect(Exact::Triangle_3(et[0], et[1], et[2]),
                                           Exact::Tetrahedron_3(eT[0], eT[1], eT[2], eT[3]));
      ASSERT_EQ(ref.closed, cgal) << "reference, trial " << trial;
    }
    // Degenerate (collinear) triangles are the faces (a, x, b) with x snapped onto a–b, which
    // faces_touching_tet(s) passes to exact_triangle_meets_tet: they are checked too.
    ASSERT_EQ(meets, ref.closed) << "trial " << trial << (is_degenerate ? " (degenerate)" : "");
    ASSERT_EQ(sh::exact_section_contact(t, T), ref.section)
        << "trial " << trial << (is_degenerate ? " (degenerate)" : "");
    {
      const Vector3d from = coord(rng) < 2 ? T[pick4(rng)] : grid(), to = grid();
      ASSERT_EQ(sh::exact_normal_dot_sign(t, from, to),
                normal_dot_sign_exact(et, exact(from), exact(to)))
          << "trial " << trial;
    }
    // Where every snapped point is a double (dyadic s on the integer grid), the snapped and the
    // plain code paths must agree.
    const Tri r = rounded(t);
    if (exact(plain(r)) == et) {
      ++dyadic;
      ASSERT_EQ(meets, sh::exact_triangle_meets_tet(plain(r), T)) << "trial " << trial;
      ASSERT_EQ(ref.section, sh::triangle_section_contact(r, T)) << "trial " << trial;
    } else if (!is_degenerate && !degenerate(exact(plain(r)))) {
      rounding_matters += sh::exact_triangle_meets_tet(plain(r), T) != meets ||
                          sh::triangle_section_contact(r, T) != ref.section;
    }
    closed += ref.closed;
    open += !ref.closed;
    section += ref.section;
    touch_only += ref.closed && !ref.section;
    degen += is_degenerate;
    degen_closed += is_degenerate && ref.closed;

    if (is_degenerate) continue;
    Tri u;
    if (pick4(rng) < 2) {
      const int j = pick4(rng);
      u = {T[k_facet[j][0]], T[k_facet[j][1]], T[k_facet[j][2]]};
    } else {
      do u = {grid(), grid(), T[pick4(rng)]};
      while (degenerate(exact(plain(u))));
    }
    ASSERT_TRUE(triangles_meet_as_reference(t, u, pairs)) << "trial " << trial;
  }
  EXPECT_GT(closed, 1200);
  EXPECT_GT(open, 250);
  EXPECT_GT(section, 800);
  EXPECT_GT(touch_only, 400);
  EXPECT_GT(degen, 30);
  EXPECT_GT(degen_closed, 20);
  EXPECT_GT(dyadic, 200);
  EXPECT_GT(rounding_matters, 100);  // the rounded points would have decided these wrongly
  EXPECT_GT(pairs.meet, 700);
  EXPECT_GT(pairs.miss, 700);
  EXPECT_GT(pairs.coplanar, 6);
}

// ------------------------------------------------- several snapped points on one segment (a chain)

// A coarse feature edge snaps its chain's input vertices onto one segment a–b, so the faces next
// to it hold two snapped points of one segment, or a snapped point and an end of its segment:
// columns q1 − q0 that are exact multiples of b − a, and every plane through a and b contains
// them. The predicates decide these by the sign of the multiple and by expanding the snapped
// points into their segment's ends; the exact rational reference must agree on every one.
TEST(SnappedPredicates, SnappedPointsOfOneSegmentMatchExactRationalReference) {
  std::mt19937 rng(4242);
  std::uniform_int_distribution<int> coord(0, 4), pick4(0, 3), pick8(0, 7);
  auto grid = [&] { return Vector3d(coord(rng), coord(rng), coord(rng)); };
  const std::array<double, 8> s_list = {1.0 / 3, 2.0 / 3, 0.1, 0.7, 1.0 / 7, 0.5, 0.25, 0.999};
  int closed = 0, open = 0, degen = 0, same_segment_faces = 0, zero_dots = 0;
  PairCounts pairs;
  for (int trial = 0; trial < 3000; ++trial) {
    Tet T;
    do T = {grid(), grid(), grid(), grid()};
    while (CGAL::orientation(exact(T[0]), exact(T[1]), exact(T[2]), exact(T[3])) == 0);
    // The segment: a tet edge, a tet corner to a grid point, or two grid points.
    Vector3d a, b;
    do {
      const int kind = pick4(rng);
      a = kind < 3 ? T[pick4(rng)] : grid();
      b = kind == 0 ? T[pick4(rng)] : grid();
    } while (a == b);
    std::array<sh::ExactPoint, 4> chain;
    for (auto& q : chain) q = sh::ExactPoint::on_segment(a, b, s_list[rng() % s_list.size()]);
    if (pick4(rng) == 0) chain[3] = sh::ExactPoint::on_segment(b, a, 0.5);  // the reversed segment
    auto corner = [&]() -> sh::ExactPoint {
      switch (pick8(rng)) {
        case 0:
        case 1:
        case 2:
          return chain[std::size_t(pick4(rng))];
        case 3:
          return a;
        case 4:
          return b;
        case 5:
          return Vector3d(T[pick4(rng)]);
        default:
          return grid();
      }
    };
    ExactTri t;
    int snapped = 0;
    do {
      t = {chain[std::size_t(pick4(rng))], corner(), corner()};
      std::swap(t[0], t[std::size_t(rng() % 3)]);
      snapped = t[0].snapped + t[1].snapped + t[2].snapped;
    } while (exact(t[0]) == exact(t[1]) || exact(t[1]) == exact(t[2]) ||
             exact(t[0]) == exact(t[2]));
    same_segment_faces += snapped >= 2;
    const std::array<EP, 3> et = exact(t);
    const std::array<EP, 4> eT = exact(T);
    const bool is_degenerate = degenerate(et);
    ASSERT_EQ(sh::exact_collinear(t), is_degenerate) << "trial " << trial;
    const Reference ref = reference(et, eT);
    ASSERT_EQ(sh::exact_triangle_meets_tet(t, T), ref.closed)
        << "trial " << trial << (is_degenerate ? " (degenerate)" : "");
    ASSERT_EQ(sh::exact_section_contact(t, T), ref.section)
        << "trial " << trial << (is_degenerate ? " (degenerate)" : "");
    {
      const Vector3d from = pick4(rng) < 2 ? a : grid(), to = pick4(rng) < 2 ? b : grid();
      const int expected = normal_dot_sign_exact(et, exact(from), exact(to));
      ASSERT_EQ(sh::exact_normal_dot_sign(t, from, to), expected) << "trial " << trial;
      zero_dots += expected == 0 && !is_degenerate;
    }
    closed += ref.closed;
    open += !ref.closed;
    degen += is_degenerate;
    if (is_degenerate) continue;
    Tri u;
    do u = {pick4(rng) < 2 ? a : grid(), pick4(rng) < 2 ? b : grid(), T[pick4(rng)]};
    while (degenerate(exact(plain(u))));
    ASSERT_TRUE(triangles_meet_as_reference(t, u, pairs)) << "trial " << trial;
  }
  EXPECT_GT(same_segment_faces, 600);
  EXPECT_GT(degen, 300);
  EXPECT_GT(closed, 1000);
  EXPECT_GT(open, 300);
  EXPECT_GT(zero_dots, 100);
  EXPECT_GT(pairs.meet, 300);
  EXPECT_GT(pairs.miss, 300);
  std::printf(
      "faces with two snapped corners %d, collinear %d, meeting the tet %d, missing %d, "
      "zero normal dots %d, triangle pairs meeting %d, missing %d\n",
      same_segment_faces, degen, closed, open, zero_dots, pairs.meet, pairs.miss);
}

// The floating-point filter in front of the exact stages (sign_det with snapped arguments) must
// never decide a sign the exact point does not have: real coordinates far from the origin (where
// a snapped point's rounding is largest against the triangle's size), segments of every length,
// and the end `to` of the tested direction placed within a few units of rounding of the exact
// triangle's plane, on either side, so that the rounded and the exact configurations disagree
// in sign on a share of the trials.
TEST(SnappedPredicates, SnappedPointsNearAPlaneAtRealScalesMatchExactRationalReference) {
  std::mt19937 rng(977);
  std::uniform_real_distribution<double> unit(-1, 1), s01(0, 1);
  int positive = 0, negative = 0, zero = 0, rounding_flips = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double offset = std::pow(10.0, double(rng() % 7)),
                 size = std::pow(10.0, -double(rng() % 7));
    const Vector3d centre = offset * Vector3d(unit(rng), unit(rng), unit(rng));
    auto near = [&] { return Vector3d(centre + size * Vector3d(unit(rng), unit(rng), unit(rng))); };
    auto snapped = [&] {
      const Vector3d a = near(), b = near();
      return sh::ExactPoint::on_segment(a, b, rng() % 8 == 0 ? 0.5 : s01(rng));
    };
    ExactTri t;
    for (auto& q : t) q = rng() % 3 == 0 ? sh::ExactPoint(near()) : snapped();
    const std::array<EP, 3> et = exact(t);
    if (degenerate(et)) continue;
    // `to`: the rounded centroid moved along the rounded normal by a multiple of the rounding
    // unit, often not at all.
    const Vector3d p0 = t[0].p, p1 = t[1].p, p2 = t[2].p;
    const Vector3d n = (p1 - p0).cross(p2 - p0).normalized();
    const double ulp =
        std::numeric_limits<double>::epsilon() * (centre.cwiseAbs().maxCoeff() + size);
    const int k = int(rng() % 9) - 4;
    const Vector3d to = (p0 + p1 + p2) / 3 + double(k) * ulp * n;
    const Vector3d from = rng() % 2 ? p0 : Vector3d(near());
    const int expected = normal_dot_sign_exact(et, exact(from), exact(to));
    ASSERT_EQ(sh::exact_normal_dot_sign(t, from, to), expected)
        << "trial " << trial << " offset " << offset << " size " << size << " k " << k;
    // The sign the rounded corners alone give (CGAL's exact orientation on them).
    const int rounded_sign = int(CGAL::orientation(inexact(p0), inexact(p1), inexact(p2),
                                                   inexact(Vector3d(p0 + to - from))));
    rounding_flips += from == p0 && rounded_sign != expected;
    positive += expected > 0;
    negative += expected < 0;
    zero += expected == 0;
  }
  // Both signs often, and the rounded corners alone wrong on some trials (the filter must not
  // decide those).
  EXPECT_GT(positive, 3000);
  EXPECT_GT(negative, 3000);
  EXPECT_GT(rounding_flips, 50);
  std::printf("positive %d, negative %d, zero %d, rounded corners giving another sign %d\n",
              positive, negative, zero, rounding_flips);
}

// ---------------------------------------------------------------- a snapped point on a tet edge

namespace {

// A tet with the segment [a, b] as an edge, and the direction w pointing away from it across that
// edge: −(c − a) − (d − a) lies outside the tet's wedge span(b − a) + cone(c − a, d − a) at the
// edge, so P + λ w + μ (b − a) (λ > 0, |μ| small) is outside the tet for every P on the edge.
struct EdgeSetup {
  Vector3d a{0.1, 0.7, 0.3}, b{1.3, 0.2, 0.9}, c{0.3, 1.6, 1.2}, d{1.1, 1.2, -0.4};
  Tet tet() const { return {a, b, c, d}; }
  Vector3d w() const { return -(c - a) - (d - a); }
  // The triangle (P, P + w ± 0.2 (b − a)) meeting the tet at P only.
  ExactTri outside(double s) const {
    const sh::ExactPoint P = sh::ExactPoint::on_segment(a, b, s);
    return {P, Vector3d(P.p + w() + 0.2 * (b - a)), Vector3d(P.p + w() - 0.2 * (b - a))};
  }
};

}  // namespace

TEST(SnappedPredicates, SnappedPointOnATetEdgeIsDecidedExactly) {
  const EdgeSetup e;
  const Tet T = e.tet();
  ASSERT_NE(sh::normal_dot_sign({e.a, e.b, e.c}, e.a, e.d), 0);
  const Vector3d inner = (e.a + e.b + e.c + e.d) / 4, inner2 = inner + 0.1 * (e.c - e.d);
  int off_line = 0, off_plane = 0, rounded_misses = 0, rounded_facet_touch_only = 0,
      unrepresentable = 0;
  for (int k = 1; k <= 100; ++k) {
    const double s = k / 101.0;
    const sh::ExactPoint P = sh::ExactPoint::on_segment(e.a, e.b, s);
    const Vector3d Pr = P.p;
    const EP eP = exact(P);
    unrepresentable += exact(sh::ExactPoint(Pr)) != eP;
    // On the line and in every plane through the edge, exactly.
    EXPECT_TRUE(sh::exact_collinear({e.a, P, e.b})) << s;
    EXPECT_TRUE(sh::exact_collinear({P, e.b, e.a})) << s;
    EXPECT_FALSE(sh::exact_collinear({e.a, P, e.c})) << s;
    EXPECT_EQ(sh::exact_normal_dot_sign({e.a, e.c, P}, e.a, e.b), 0) << s;
    EXPECT_EQ(sh::exact_normal_dot_sign({P, e.c, e.d}, e.a, e.b),
              sh::normal_dot_sign({e.a, e.c, e.d}, e.a, e.b))
        << s;  // det[c − P, d − P, b − a] = det[c − a, d − a, b − a]: P − a ∥ b − a
    EXPECT_EQ(sh::exact_normal_dot_sign({e.a, e.c, P}, e.a, e.d),
              sh::normal_dot_sign({e.a, e.c, e.b}, e.a, e.d))
        << s;  // det[c − a, s (b − a), d − a], s > 0
    off_line += !sh::exact_collinear({e.a, Pr, e.b});
    off_plane += sh::normal_dot_sign({e.a, e.c, Pr}, e.a, e.b) != 0;

    // Touching at the edge point only: contact, but not section contact.
    const ExactTri out = e.outside(s);
    EXPECT_TRUE(sh::exact_triangle_meets_tet(out, T)) << s;
    EXPECT_FALSE(sh::exact_section_contact(out, T)) << s;
    rounded_misses += !sh::exact_triangle_meets_tet(plain(rounded(out)), T);
    // Entering the tet from P: section contact.
    const ExactTri in = {P, inner, inner2};
    EXPECT_TRUE(sh::exact_triangle_meets_tet(in, T)) << s;
    EXPECT_TRUE(sh::exact_section_contact(in, T)) << s;
    // Lying in the facet (a, b, c) with a corner on its edge: coplanar section contact.
    const ExactTri flat = {P, e.c, e.a};
    EXPECT_TRUE(sh::exact_triangle_meets_tet(flat, T)) << s;
    EXPECT_TRUE(sh::exact_section_contact(flat, T)) << s;
    rounded_facet_touch_only += !sh::triangle_section_contact({Pr, e.c, e.a}, T);
    // Against the facet (a, b, c) as a triangle: coplanar for `flat`, a touch at P for `out`.
    EXPECT_TRUE(sh::exact_triangles_meet(flat, {e.a, e.b, e.c})) << s;
    EXPECT_TRUE(sh::exact_triangles_meet(out, {e.a, e.b, e.c})) << s;
    EXPECT_TRUE(sh::exact_triangles_meet(out, {e.b, e.d, e.a})) << s;
    // ... and a triangle across the edge's line short of P misses it.
    const Vector3d before = e.a + 0.5 * s * (e.b - e.a);
    EXPECT_FALSE(sh::exact_triangles_meet(out, {e.a, before, e.c})) << s;
  }
  // The snapped points are mostly not doubles, and their roundings leave the line, the planes
  // through the edge and the tet for some s: the plain predicates on them would decide otherwise.
  EXPECT_GT(unrepresentable, 50);
  EXPECT_GT(off_line, 0);
  EXPECT_GT(off_plane, 0);
  EXPECT_GT(rounded_misses, 0);
  EXPECT_GT(rounded_facet_touch_only, 0);
}

// ---------------------------------------------------------------- InputSurfaceIndex snapping

namespace {

// Vertices: 0 = a, 1 = b (the coarse feature edge), 2 = x (to be snapped onto a–b, originally
// off it, outside the tet), 3, 4 = x's neighbours outside the tet, 5 far away.
struct SnapSurface {
  EdgeSetup e;
  double s = 0;
  Eigen::MatrixXd V;
  explicit SnapSurface(double s_) : s(s_), V(6, 3) {
    const Vector3d Pr = sh::ExactPoint::on_segment(e.a, e.b, s).p, w = e.w();
    V.row(0) = e.a.transpose();
    V.row(1) = e.b.transpose();
    V.row(2) = (Pr + 0.3 * w).transpose();
    V.row(3) = (Pr + w + 0.2 * (e.b - e.a)).transpose();
    V.row(4) = (Pr + w - 0.2 * (e.b - e.a)).transpose();
    V.row(5) = (Pr + 2 * w).transpose();
  }
  Vector3d x() const { return V.row(2).transpose(); }
  // A small tet around P (P inside it).
  Tet small() const {
    const Vector3d Pr = sh::ExactPoint::on_segment(e.a, e.b, s).p;
    return {Vector3d(Pr + 0.01 * Vector3d(1, 1, 1)), Vector3d(Pr + 0.01 * Vector3d(1, -1, -1)),
            Vector3d(Pr + 0.01 * Vector3d(-1, 1, -1)), Vector3d(Pr + 0.01 * Vector3d(-1, -1, 1))};
  }
};

// The first s = k / 101 whose snapped point rounds to a point strictly outside the tet.
double rounding_outside_s() {
  const EdgeSetup e;
  for (int k = 1; k <= 100; ++k) {
    const double s = k / 101.0;
    if (!sh::exact_triangle_meets_tet(plain(rounded(e.outside(s))), e.tet())) return s;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

TEST(SnappedPredicates, InputSurfaceIndexSeesTheSnappedFaces) {
  const double s = rounding_outside_s();
  ASSERT_FALSE(std::isnan(s));
  const SnapSurface surf(s);
  const EdgeSetup& e = surf.e;
  const Tet T = e.tet(), small = surf.small();
  Eigen::MatrixXi F(3, 3);
  F << 2, 3, 4,  // moved, meets the tet at P only once snapped
      3, 5, 4,   // never moved, far
      0, 2, 1;   // moved, becomes the segment [a, b] (degenerate) once snapped
  sh::InputSurfaceIndex index(surf.V, F);
  const sh::SnappedVertex snap{2, 0, 1, s};
  const Vector3d P = sh::ExactPoint::on_segment(e.a, e.b, s).p;
  ASSERT_EQ(P, Vector3d(e.a + s * (e.b - e.a)));

  auto check_unsnapped = [&](const char* when) {
    SCOPED_TRACE(when);
    EXPECT_EQ(index.snap_of(2), nullptr);
    EXPECT_TRUE(index.snaps().empty());
    EXPECT_EQ(index.face_triangle(0)[0], surf.x());
    EXPECT_EQ(index.face_triangle(2)[1], surf.x());
    EXPECT_EQ(index.faces_touching_tet(T), std::vector<int>{2});  // (a, x, b) along the edge
    EXPECT_FALSE(index.face_touches_tet(0, T));
    EXPECT_TRUE(index.face_touches_tet(2, T));
    EXPECT_FALSE(index.face_section_contact(2, T));
    EXPECT_EQ(index.faces_touching_tet(small), std::vector<int>{2});  // its edge a–b crosses
    EXPECT_FALSE(index.face_section_contact(0, small));
    EXPECT_TRUE(index.face_section_contact(2, small));
    EXPECT_EQ(index.faces_touching_tets({T, small}), std::vector<int>{2});
    EXPECT_FALSE(index.face_degenerate(2));
    EXPECT_NE(index.face_normal_dot_sign(2, e.a, e.c), 0);
    EXPECT_EQ(index.face_normal_dot_sign(2, e.a, e.c),
              sh::normal_dot_sign({e.a, surf.x(), e.b}, e.a, e.c));
  };
  auto check_snapped = [&](const sh::InputSurfaceIndex& idx, const char* when) {
    SCOPED_TRACE(when);
    const sh::SnappedVertex* q = idx.snap_of(2);
    ASSERT_NE(q, nullptr);
    EXPECT_EQ(q->vertex, 2);
    EXPECT_EQ(q->a, 0);
    EXPECT_EQ(q->b, 1);
    EXPECT_EQ(q->s, s);
    for (int v : {0, 1, 3, 4, 5}) EXPECT_EQ(idx.snap_of(v), nullptr) << v;
    ASSERT_EQ(idx.snaps().size(), 1u);
    EXPECT_EQ(idx.snaps()[0].vertex, 2);
    EXPECT_EQ(idx.snaps()[0].s, s);
    // The rounded snapped position, the unmoved corners unchanged.
    EXPECT_EQ(idx.face_triangle(0)[0], P);
    EXPECT_EQ(idx.face_triangle(0)[1], Vector3d(surf.V.row(3).transpose()));
    EXPECT_EQ(idx.face_triangle(2)[1], P);
    EXPECT_EQ(idx.face_triangle(1)[0], Vector3d(surf.V.row(3).transpose()));
    // The rounded face misses the tet; the exact snapped one touches it at P.
    ASSERT_FALSE(sh::exact_triangle_meets_tet(plain(idx.face_triangle(0)), T));
    EXPECT_TRUE(idx.face_touches_tet(0, T));
    EXPECT_FALSE(idx.face_section_contact(0, T));
    EXPECT_TRUE(idx.face_touches_tet(2, T));
    EXPECT_FALSE(idx.face_section_contact(2, T));  // the segment [a, b] is the tet's edge
    EXPECT_FALSE(idx.face_touches_tet(1, T));
    EXPECT_EQ(idx.faces_touching_tet(T), (std::vector<int>{0, 2}));
    EXPECT_EQ(idx.faces_touching_tet(small), (std::vector<int>{0, 2}));
    EXPECT_TRUE(idx.face_section_contact(0, small));
    EXPECT_TRUE(idx.face_section_contact(2, small));  // the segment crosses the open small tet
    EXPECT_EQ(idx.faces_touching_tets({T, small}), (std::vector<int>{0, 2}));
    EXPECT_EQ(idx.faces_touching_tets({T}), (std::vector<int>{0, 2}));
    // (a, P, b) is exactly degenerate: zero normal.
    EXPECT_TRUE(idx.face_degenerate(2));
    EXPECT_FALSE(idx.face_degenerate(0));
    EXPECT_FALSE(idx.face_degenerate(1));
    EXPECT_EQ(idx.face_normal_dot_sign(2, e.a, e.c), 0);
    EXPECT_EQ(idx.face_normal_dot_sign(2, e.c, e.d), 0);
    const ExactTri moved = {sh::ExactPoint::on_segment(e.a, e.b, s),
                            Vector3d(surf.V.row(3).transpose()),
                            Vector3d(surf.V.row(4).transpose())};
    EXPECT_EQ(idx.face_normal_dot_sign(0, e.a, e.c), sh::exact_normal_dot_sign(moved, e.a, e.c));
    EXPECT_NE(idx.face_normal_dot_sign(0, e.a, e.c), 0);
  };

  check_unsnapped("input");
  index.snap_vertex(snap);
  check_snapped(index, "snapped");
  {
    const sh::InputSurfaceIndex built(surf.V, F, {snap});
    check_snapped(built, "constructed with the snap");
  }
  // Snapping again moves the point; snapping back restores the answers.
  index.snap_vertex({2, 0, 1, 0.5});
  EXPECT_EQ(index.snap_of(2)->s, 0.5);
  EXPECT_EQ(index.face_triangle(0)[0], Vector3d(e.a + 0.5 * (e.b - e.a)));
  index.snap_vertex(snap);
  check_snapped(index, "snapped twice");
  index.unsnap_vertex(2);
  check_unsnapped("unsnapped");
  index.unsnap_vertex(2);  // not snapped: no effect
  index.unsnap_vertex(4);
  check_unsnapped("unsnapped twice");
  index.snap_vertex(snap);
  check_snapped(index, "snapped after unsnapping");
}

TEST(SnappedPredicates, TriangleIntersectsSeesTheSnappedFaces) {
  const double s = rounding_outside_s();
  ASSERT_FALSE(std::isnan(s));
  const SnapSurface surf(s);
  const EdgeSetup& e = surf.e;
  Eigen::MatrixXi F(2, 3);
  F << 2, 3, 4, 3, 5, 4;
  sh::InputSurfaceIndex index(surf.V, F);
  const Tri facet = {e.a, e.b, e.c}, other = {e.a, e.b, e.d};
  const std::array<bool, 3> none = {false, false, false};
  const Eigen::Vector3i ids(-1, -1, -1);
  EXPECT_FALSE(index.triangle_intersects(facet, none, ids));
  EXPECT_FALSE(index.triangle_intersects(other, none, ids));
  index.snap_vertex({2, 0, 1, s});
  // The moved face (P, 3, 4) touches both tet facets through a–b at P; its rounding touches neither
  // (it misses the whole tet).
  ASSERT_FALSE(sh::exact_triangles_meet(plain(index.face_triangle(0)), facet));
  ASSERT_FALSE(sh::exact_triangles_meet(plain(index.face_triangle(0)), other));
  EXPECT_TRUE(index.triangle_intersects(facet, none, ids));
  EXPECT_TRUE(index.triangle_intersects(other, none, ids));
  // A triangle across the line a–b short of P still misses it.
  const Tri before = {e.a, Vector3d(e.a + 0.5 * s * (e.b - e.a)), e.c};
  EXPECT_FALSE(index.triangle_intersects(before, none, ids));
  index.unsnap_vertex(2);
  EXPECT_FALSE(index.triangle_intersects(facet, none, ids));
  EXPECT_FALSE(index.triangle_intersects(other, none, ids));
}

TEST(SnappedPredicates, BadSnapsThrow) {
  const SnapSurface surf(0.5);
  Eigen::MatrixXi F(3, 3);
  F << 2, 3, 4, 3, 5, 4, 0, 2, 1;
  sh::InputSurfaceIndex index(surf.V, F);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const sh::SnappedVertex& bad :
       std::vector<sh::SnappedVertex>{{2, 0, 1, 0.0},  // s = 0: the vertex a itself
                                      {2, 0, 1, 1.0},  // s = 1
                                      {2, 0, 1, -0.25},
                                      {2, 0, 1, 1.5},
                                      {2, 0, 1, nan},
                                      {2, 2, 1, 0.5},   // a == vertex
                                      {2, 0, 2, 0.5},   // b == vertex
                                      {-1, 0, 1, 0.5},  // out of range
                                      {6, 0, 1, 0.5},
                                      {2, 6, 1, 0.5},
                                      {2, 0, -1, 0.5}}) {
    EXPECT_THROW(index.snap_vertex(bad), std::invalid_argument)
        << bad.vertex << " " << bad.a << " " << bad.b << " " << bad.s;
    EXPECT_THROW(sh::InputSurfaceIndex(surf.V, F, {bad}), std::invalid_argument);
  }
  // Nothing was snapped by the failed calls.
  EXPECT_TRUE(index.snaps().empty());
  // An end given by its position (restore_input_ids: a coarse vertex that is no vertex here)
  // snaps like the vertex at that position.
  {
    sh::InputSurfaceIndex by_id(surf.V, F), by_position(surf.V, F);
    by_id.snap_vertex({2, 0, 1, 0.5});
    sh::SnappedVertex q{2, 0, -1, 0.5};
    q.pb = surf.V.row(1).transpose();
    by_position.snap_vertex(q);
    EXPECT_EQ(by_id.reference_V(), by_position.reference_V());
    EXPECT_EQ(by_id.face_triangle(0), by_position.face_triangle(0));
  }
  EXPECT_EQ(index.face_triangle(0)[0], surf.x());
  // A good snap after bad ones works, and a bad one leaves it in place.
  index.snap_vertex({2, 0, 1, 0.25});
  EXPECT_THROW(index.snap_vertex({2, 0, 1, 1.0}), std::invalid_argument);
  ASSERT_NE(index.snap_of(2), nullptr);
  EXPECT_EQ(index.snap_of(2)->s, 0.25);
  EXPECT_EQ(index.face_triangle(2)[1], sh::ExactPoint::on_segment(surf.e.a, surf.e.b, 0.25).p);
}

// A snapped vertex and a rounded point of the same line: the face they make with the line's end
// is not exactly degenerate, yet flattened to rounding (CGAL's part.off, shape-refined: a
// bisection point p of the input edge a–b next to a 3e-3-high cap whose chain vertex x snaps onto
// a–b). face_degenerate cannot see it; face_area_ratio does.
TEST(SnappedPredicates, AFaceFlattenedToRoundingIsCollapsedThoughNotExactlyDegenerate) {
  const Vector3d a(0, 0, 0), b(1, 1.0 / 3.0, 0.2);
  // p: b scaled by 0.7 and rounded, off the exact line a–b unless the rounding happens to
  // vanish (checked below), x: 3e-3 off the line.
  Eigen::MatrixXd V(4, 3);
  V.row(0) = a.transpose();
  V.row(1) = b.transpose();
  V.row(2) = (0.7 * b).transpose();
  V.row(3) = (0.4 * b + Vector3d(0, 3e-3, -2e-3)).transpose();
  Eigen::MatrixXi F(2, 3);
  F << 0, 3, 2,  // x between a and p: flattened once x snaps onto a–b
      2, 3, 1;   // p, x, b: flattened too
  const sh::SnappedVertex snap{3, 0, 1, 0.4};
  const sh::InputSurfaceIndex before(V, F);
  EXPECT_GT(before.face_area_ratio(0), 0.999);
  EXPECT_LT(before.face_area_ratio(0), 1.001);
  const sh::InputSurfaceIndex after(V, F, {snap});
  int rounded_off_line = 0;
  for (int f = 0; f < 2; ++f) {
    rounded_off_line += !after.face_degenerate(f);
    EXPECT_LT(after.face_area_ratio(f), sh::k_min_reference_area_ratio) << f;
  }
  // The point of the test: at least one of them is not exactly degenerate.
  EXPECT_GT(rounded_off_line, 0);
  // A face without a snapped corner keeps its area.
  Eigen::MatrixXi G(1, 3);
  G << 0, 1, 3;
  EXPECT_DOUBLE_EQ(sh::InputSurfaceIndex(V, G).face_area_ratio(0), 1.0);
}
