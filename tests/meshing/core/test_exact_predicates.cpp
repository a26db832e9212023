// meshing/core/exact_predicates (no CGAL) against CGAL's exact-predicates kernel, on inputs built
// to be degenerate or within rounding of it: nearly coplanar points, exactly coplanar points on
// grids, segments through triangle edges and corners, and coplanar segments.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>

#include "meshing/core/exact_predicates.hpp"

using Eigen::Vector3d;
namespace ex = curvefem::exact;

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
K::Point_3 pt(const Vector3d& v) { return {v.x(), v.y(), v.z()}; }

int cgal_orient3d(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  return int(CGAL::orientation(pt(a), pt(b), pt(c), pt(d)));
}

bool cgal_segment_triangle(const Vector3d& p, const Vector3d& q, const Vector3d& a,
                           const Vector3d& b, const Vector3d& c) {
  return CGAL::do_intersect(K::Segment_3(pt(p), pt(q)), K::Triangle_3(pt(a), pt(b), pt(c)));
}

struct Gen {
  std::mt19937 rng{11};
  std::uniform_real_distribution<double> U{-1, 1};
  Vector3d point(double scale = 1) { return scale * Vector3d(U(rng), U(rng), U(rng)); }
  double u() { return 0.5 * (U(rng) + 1); }
  // A point of the plane of (a, b, c), rounded: exactly on it or just off.
  Vector3d on_plane(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
    return a + u() * (b - a) + u() * (c - a);
  }
  // A point of the grid z = const with coordinates multiples of 2^-10 (exactly coplanar).
  Vector3d grid(double z) {
    return {std::round(U(rng) * 1024) / 1024, std::round(U(rng) * 1024) / 1024, z};
  }
};

}  // namespace

TEST(ExactPredicates, Orient3dAgreesWithCgalOnNearlyAndExactlyCoplanarPoints) {
  Gen g;
  int zero = 0, nonzero = 0, filtered_out = 0;
  for (int i = 0; i < 20000; ++i) {
    const double scale = i % 3 == 0 ? 1e-6 : (i % 3 == 1 ? 1.0 : 1e4);
    const Vector3d a = g.point(scale), b = g.point(scale), c = g.point(scale);
    Vector3d d;
    switch (i % 4) {
      case 0:
        d = g.on_plane(a, b, c);
        break;
      case 1:
        d = a + g.u() * (b - a);
        break;  // near the line a b
      case 2: {
        const double z = std::round(g.U(g.rng) * 64) / 64;
        const Vector3d p = g.grid(z), q = g.grid(z), r = g.grid(z), s = g.grid(z);
        const int o = ex::orient3d(p, q, r, s);
        EXPECT_EQ(o, 0);
        EXPECT_EQ(o, cgal_orient3d(p, q, r, s));
        ++zero;
        continue;
      }
      default:
        d = g.point(scale);
        break;
    }
    const int o = ex::orient3d(a, b, c, d);
    ASSERT_EQ(o, cgal_orient3d(a, b, c, d)) << i;
    // the floating-point determinant with the same operands; count where its sign is wrong
    const double fl = (b - a).dot((c - a).cross(d - a));
    filtered_out += (fl > 0 ? 1 : (fl < 0 ? -1 : 0)) != o;
    (o == 0 ? zero : nonzero) += 1;
    // orientation flips with an odd permutation
    EXPECT_EQ(ex::orient3d(b, a, c, d), -o);
  }
  std::printf("orient3d: %d zero, %d nonzero, %d where plain floating point has the wrong sign\n",
              zero, nonzero, filtered_out);
  EXPECT_GE(zero, 5000);
  EXPECT_GT(filtered_out, 100);  // the cases exercise the exact path
}

TEST(ExactPredicates, CollinearityAndContainmentAreExact) {
  const Vector3d a(0.1, 0.2, 0.3), b(0.7, -0.4, 0.9);
  // 0.1 + 0.5·0.6 is not exact in binary: the midpoint computed in floating point is (in general)
  // off the line, and collinear() must see that exactly, as CGAL does.
  Gen g;
  int off = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vector3d m = a + g.u() * (b - a);
    const bool ours = ex::collinear(a, b, m);
    EXPECT_EQ(ours, CGAL::collinear(pt(a), pt(b), pt(m)));
    off += !ours;
  }
  EXPECT_GT(off, 100);
  EXPECT_TRUE(ex::collinear(a, b, a));
  EXPECT_TRUE(ex::collinear(Vector3d(0, 0, 0), Vector3d(1, 1, 1), Vector3d(0.5, 0.5, 0.5)));
  const Vector3d c(0.25, 0.75, -0.5);
  EXPECT_TRUE(ex::triangle_contains(a, b, c, a));
  EXPECT_FALSE(ex::triangle_contains(a, b, a, a));  // degenerate: contains nothing
  for (int i = 0; i < 2000; ++i) {
    const Vector3d x = g.on_plane(a, b, c);
    EXPECT_EQ(ex::triangle_contains(a, b, c, x), K::Triangle_3(pt(a), pt(b), pt(c)).has_on(pt(x)));
  }
  // exactly coplanar grid points, inside, on edges and outside
  const Vector3d p(0, 0, 0.5), q(1, 0, 0.5), r(0, 1, 0.5);
  EXPECT_TRUE(ex::triangle_contains(p, q, r, Vector3d(0.5, 0.5, 0.5)));
  EXPECT_TRUE(ex::triangle_contains(p, q, r, Vector3d(0.25, 0.25, 0.5)));
  EXPECT_FALSE(ex::triangle_contains(p, q, r, Vector3d(0.5, 0.5 + 0x1p-52, 0.5)));
  EXPECT_FALSE(ex::triangle_contains(p, q, r, Vector3d(0.25, 0.25, 0.5 + 0x1p-53)));
}

TEST(ExactPredicates, SegmentTriangleAgreesWithCgalThroughEdgesCornersAndInThePlane) {
  Gen g;
  int hits = 0, misses = 0, coplanar = 0;
  for (int i = 0; i < 20000; ++i) {
    const double scale = i % 2 ? 1.0 : 1e-7;
    Vector3d a = g.point(scale), b = g.point(scale), c = g.point(scale);
    Vector3d p, q;
    const Vector3d n = (b - a).cross(c - a);
    switch (i % 5) {
      case 0: {  // through a point of an edge (rounded), both ways
        const Vector3d x = a + g.u() * (b - a);
        p = x + g.u() * n, q = x - g.u() * n;
        break;
      }
      case 1:  // through a corner
        p = b + g.u() * n, q = b - g.u() * n;
        break;
      case 2: {  // ending on the plane (at a rounded point of it)
        const Vector3d x = g.on_plane(a, b, c);
        p = x, q = x + g.U(g.rng) * n;
        break;
      }
      case 3: {  // coplanar: an exact grid plane
        const double z = 0.25;
        a = g.grid(z), b = g.grid(z), c = g.grid(z);
        p = g.grid(z), q = g.grid(z);
        if (i % 10 == 3) q = p + 0.5 * (a - p);  // toward a corner: often ending inside
        ++coplanar;
        break;
      }
      default:  // anywhere
        p = g.point(scale), q = g.point(scale);
    }
    if (CGAL::collinear(pt(a), pt(b), pt(c)) || p == q) continue;
    const bool ours = ex::segment_meets_triangle(p, q, a, b, c);
    ASSERT_EQ(ours, cgal_segment_triangle(p, q, a, b, c)) << i;
    (ours ? hits : misses) += 1;
  }
  std::printf("segment-triangle: %d meet, %d miss, %d coplanar cases\n", hits, misses, coplanar);
  EXPECT_GT(hits, 4000);
  EXPECT_GT(misses, 4000);
  // hand-made: a segment lying along an edge, touching a corner, missing by one ulp
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(ex::segment_meets_triangle({-1, 0, 0}, {2, 0, 0}, a, b, c));
  EXPECT_TRUE(ex::segment_meets_triangle({-1, -1, 0}, {0, 0, 0}, a, b, c));
  EXPECT_FALSE(ex::segment_meets_triangle({-1, -1, 0}, {-0x1p-60, -0x1p-60, 0}, a, b, c));
  EXPECT_TRUE(ex::segment_meets_triangle({0.5, 0.5, 1}, {0.5, 0.5, -1}, a, b, c));
  EXPECT_FALSE(
      ex::segment_meets_triangle({0.5, 0.5 + 0x1p-52, 1}, {0.5, 0.5 + 0x1p-52, -1}, a, b, c));
  EXPECT_TRUE(ex::segment_meets_triangle({0.25, 0.25, 0}, {0.25, 0.25, 1}, a, b, c));
  EXPECT_FALSE(ex::segment_meets_triangle({0.25, 0.25, 0x1p-80}, {0.25, 0.25, 1}, a, b, c));
  EXPECT_FALSE(ex::segment_meets_triangle(a, a, a, b, c));  // a point is no segment
}
