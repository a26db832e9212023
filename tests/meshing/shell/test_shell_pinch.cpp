// Pinch points (singular shell vertices: base = mid = top, a zero-length pillar) under the shell
// projection. The fiber at a pinch corner is the pinch point itself, and near it the rounded
// fiber is ~1e-16 long: P must still reach the input there (the crater of test_shell_bevel.cpp,
// needles whose tip is an isolated singular vertex), and P⁻¹ then P must return every input
// vertex. The wedge predicate behind this is checked against exact rational arithmetic.

#include <CGAL/Exact_rational.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "meshing/core/adversarial.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/shell/bevel.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"
#include "meshing/shell/verify.hpp"
#include "tests/support/test_support.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;
using Eigen::Vector3d;

namespace {

SurfaceMesh crater() { return curvefem::test::crater_mesh(); }

// A needle: the tip 0 over a ring of n vertices of radius about r at z = 0, closed by the centre
// n + 1. The faces at the tip lean less than 0.5° from the vertical: no direction sees them all
// (tolerance 1e-2), so the tip is an isolated singular vertex. `jitter` moves the ring vertices
// and the tip off the regular shape.
SurfaceMesh needle(int n, double r, std::mt19937* rng = nullptr) {
  std::uniform_real_distribution<double> jitter(-0.25, 0.25);
  auto j = [&] { return rng ? jitter(*rng) : 0.0; };
  SurfaceMesh s;
  s.V.resize(n + 2, 3);
  s.V.row(0) << 0.013 + 0.01 * j(), -0.021 + 0.01 * j(), 1.0;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * (i + 0.31 + 0.5 * j()) / n, ri = r * (1 + j());
    s.V.row(1 + i) << ri * std::cos(a), ri * std::sin(a), 0.0;
  }
  s.V.row(n + 1) << 0.0007, 0.0003, 0.0;
  s.F.resize(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    const int a = 1 + i, b = 1 + (i + 1) % n;
    s.F.row(i) << 0, a, b;
    s.F.row(n + i) << n + 1, b, a;
  }
  return s;
}

struct Case {
  sh::Shell shell;
  SurfaceMesh surface;  // the surface the shell was built on (beveled or not)
  int singular = 0;
};

Case plain_shell(const SurfaceMesh& input) {
  sh::ShellStats stats;
  Case c{sh::build_shell(input, {}, stats), input, stats.singular_vertices};
  return c;
}

Case beveled_shell(const SurfaceMesh& input) {
  sh::ShellStats stats;
  sh::BeveledShell b = sh::build_beveled_shell(input, {}, stats);
  return {std::move(b.shell), std::move(b.surface.mesh), stats.singular_vertices};
}

bool pinched(const sh::Shell& s, int v) {
  return s.base.row(v) == s.mid.row(v) && s.top.row(v) == s.mid.row(v);
}

// P⁻¹ then P at every input vertex, and once more from the result: 0 failures, the largest
// error relative to the bbox edge returned. Pinch points must come back exactly, at their
// corner (h = 0).
double roundtrip_every_vertex(const Case& c) {
  const sh::ShellProjection p(c.shell, c.surface);
  const double unit = curvefem::bbox_longest_edge(c.surface.V);
  double worst = 0;
  for (int x = 0; x < c.surface.num_vertices(); ++x) {
    const Vector3d point = c.surface.V.row(x);
    const auto q = p.unproject(point);
    EXPECT_TRUE(q.has_value()) << "vertex " << x;
    if (!q) continue;
    const auto back = q ? p.project(*q) : std::nullopt;
    EXPECT_TRUE(back.has_value()) << "vertex " << x;
    if (!back) continue;
    worst = std::max(worst, (back->position - point).norm() / unit);
    EXPECT_NEAR(back->bary.sum(), 1.0, 1e-15);
    const auto again = p.unproject(back->position);
    const auto twice = again ? p.project(*again) : std::nullopt;
    EXPECT_TRUE(twice.has_value()) << "vertex " << x;
    if (twice) worst = std::max(worst, (twice->position - point).norm() / unit);
  }
  for (int v = 0; v < c.shell.mid.rows(); ++v) {
    if (!pinched(c.shell, v)) continue;
    const Vector3d x = c.shell.mid.row(v);
    const auto q = p.unproject(x);
    EXPECT_TRUE(q.has_value()) << "pinch " << v;
    if (!q) continue;
    const Eigen::Vector3i F = c.shell.F.row(q->face);
    const int r = sh::min_rotation(F);
    const int corner = q->u == 1 ? 1 : q->v == 1 ? 2 : 0;
    EXPECT_EQ(F[(r + corner) % 3], v) << "pinch " << v;
    EXPECT_EQ(q->u + q->v, corner == 0 ? 0.0 : 1.0);
    EXPECT_EQ(q->h, 0.0);
    const auto back = p.project(*q);
    EXPECT_TRUE(back.has_value()) << "pinch " << v;
    if (back) {
      EXPECT_TRUE(back->position == x) << "pinch " << v;
    }
  }
  return worst;
}

// Fibers at (u, v) within e of a pinch corner, e from 0 to 1e-6, along both edges and into the
// face, and with (u, v) rounded a little outside the triangle (as a barycentric solve gives
// them): P must reach an input face around the pinch point. The fiber at e is the image of the
// fiber at e_ref under the homothety of centre x and ratio e / e_ref, and so is its input point
// (the input is a cone around x): checked against e_ref = 1e-6, where the fiber is long enough
// for the search on the rounded fiber, to 1e-14 of the bbox edge (measured: 5e-15 where the
// search on the rounded fiber hits, 1e-16 where the pinch fallback decides). Returns the number
// of projections checked.
int check_near_pinch_corners(const Case& c) {
  const sh::ShellProjection p(c.shell, c.surface);
  const sh::InputSurfaceIndex index(c.surface.V, c.surface.F);
  const double unit = curvefem::bbox_longest_edge(c.surface.V);
  const double e_ref = 1e-6;
  int checked = 0;
  for (int f = 0; f < c.shell.F.rows(); ++f) {
    const Eigen::Vector3i F = c.shell.F.row(f);
    const int r = sh::min_rotation(F);
    for (int s = 0; s < 3; ++s) {
      const int v = F[(r + s) % 3];
      if (!pinched(c.shell, v)) continue;
      const Vector3d x = c.shell.mid.row(v);
      const std::vector<int> star = index.faces_containing(x);
      EXPECT_FALSE(star.empty()) << "pinch " << v;
      // Directions in weights (w_s, w_s+1, w_s+2): along the two edges, into the face, and
      // slightly outside it.
      const std::array<std::array<double, 3>, 4> dirs{
          {{-1, 1, 0}, {-1, 0, 1}, {-1, 0.3, 0.7}, {-0.3, 1.0, -0.7}}};
      for (const auto& d : dirs) {
        auto at = [&](double e) {
          double w[3];
          for (int k = 0; k < 3; ++k) w[(s + k) % 3] = (k == 0 ? 1.0 : 0.0) + e * d[k];
          return p.project(sh::PrismPoint{f, w[1], w[2], 0.0});
        };
        const auto ref = at(e_ref);
        const bool outside = d[2] < 0;
        if (!outside) {
          EXPECT_TRUE(ref.has_value()) << "face " << f;
          if (!ref) continue;
        }
        for (double e : {0.0, 1e-18, 1e-17, 5e-17, 1e-16, 3e-16, 1e-15, 1e-14, 1e-13, 1e-12, 1e-11,
                         1e-10, 1e-9, 1e-8}) {
          const auto hit = at(e);
          ++checked;
          EXPECT_TRUE(hit.has_value()) << "face " << f << " corner " << s << " e " << e;
          if (!hit) continue;
          EXPECT_TRUE(std::binary_search(star.begin(), star.end(), hit->face))
              << "face " << f << " e " << e;
          EXPECT_GE(hit->bary.minCoeff(), -1e-12);
          EXPECT_NEAR(hit->bary.sum(), 1.0, 1e-15);
          if (outside) {  // a fiber outside the prism: near x, no exact reference
            EXPECT_LE((hit->position - x).norm(), 10 * e + 1e-15 * unit);
            continue;
          }
          const Vector3d expected = x + (e / e_ref) * (ref->position - x);
          EXPECT_LE((hit->position - expected).norm(), 1e-14 * unit)
              << "face " << f << " corner " << s << " e " << e;
        }
      }
    }
  }
  return checked;
}

// Exact rational brute force for segment_crosses_wedge.
using Q = CGAL::Exact_rational;
struct Q3 {
  Q x, y, z;
};
Q3 q3(const Vector3d& p) { return {Q(p.x()), Q(p.y()), Q(p.z())}; }
Q3 sub(const Q3& a, const Q3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Q3 cross(const Q3& a, const Q3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
Q dot(const Q3& a, const Q3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

bool crosses_wedge_exact(const Vector3d& p, const Vector3d& q, const Vector3d& apex,
                         const Vector3d& a, const Vector3d& b) {
  const Q3 P = q3(apex), A = sub(q3(a), P), B = sub(q3(b), P);
  const Q3 n = cross(A, B);
  if (dot(n, n) == 0) return false;
  const Q sp = dot(n, sub(q3(p), P)), sq = dot(n, sub(q3(q), P));
  if ((sp == 0 && sq == 0) || (sp > 0 && sq > 0) || (sp < 0 && sq < 0)) return false;
  const Q tau = sp / (sp - sq);
  const Q3 p0 = sub(q3(p), P), d0 = sub(q3(q), q3(p));
  const Q3 d{p0.x + tau * d0.x, p0.y + tau * d0.y, p0.z + tau * d0.z};
  return dot(n, cross(d, B)) >= 0 && dot(n, cross(A, d)) >= 0;  // α, β ≥ 0
}

}  // namespace

TEST(ShellPinch, WedgeCrossingMatchesExactArithmetic) {
  const Vector3d o(0, 0, 0), ex(1, 0, 0), ey(0, 1, 0);
  // Inside, beyond the edge a–b (the wedge is unbounded), in the opposite wedge, through the apex,
  // along the ray to a, outside the ray (past the apex), ending on the plane, lying in it.
  EXPECT_TRUE(sh::segment_crosses_wedge({0.1, 0.1, -1}, {0.1, 0.1, 1}, o, ex, ey));
  EXPECT_TRUE(sh::segment_crosses_wedge({5, 7, 1}, {5, 7, -1}, o, ex, ey));
  EXPECT_FALSE(sh::segment_crosses_wedge({-0.1, -0.1, -1}, {-0.1, -0.1, 1}, o, ex, ey));
  EXPECT_TRUE(sh::segment_crosses_wedge({0, 0, -1}, {0, 0, 1}, o, ex, ey));
  EXPECT_TRUE(sh::segment_crosses_wedge({3, 0, -1}, {3, 0, 2}, o, ex, ey));
  EXPECT_FALSE(sh::segment_crosses_wedge({-3, 0, -1}, {-3, 0, 2}, o, ex, ey));
  EXPECT_TRUE(sh::segment_crosses_wedge({0.5, 0.5, 0}, {0.5, 0.5, 2}, o, ex, ey));
  EXPECT_FALSE(sh::segment_crosses_wedge({0.5, 0.5, 1}, {0.5, 0.5, 2}, o, ex, ey));
  EXPECT_FALSE(sh::segment_crosses_wedge({0.2, 0.1, 0}, {0.1, 0.2, 0}, o, ex, ey));
  EXPECT_FALSE(sh::segment_crosses_wedge({0.1, 0.1, -1}, {0.1, 0.1, 1}, o, ex, {2, 0, 0}));
  // Small integer configurations (many exactly degenerate) against rational arithmetic.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> c(-2, 2);
  auto point = [&] { return Vector3d(c(rng), c(rng), c(rng)); };
  int crossing = 0;
  for (int trial = 0; trial < 8000; ++trial) {
    const Vector3d p = point(), q = point(), apex = point(), a = point(), b = point();
    const bool expected = crosses_wedge_exact(p, q, apex, a, b);
    ASSERT_EQ(sh::segment_crosses_wedge(p, q, apex, a, b), expected) << trial;
    crossing += expected;
  }
  EXPECT_GT(crossing, 400);
  // Tiny segments next to the apex of a generic wedge (the fibers near a pinch point).
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    const Vector3d apex(u(rng), u(rng), u(rng)), a = apex + Vector3d(u(rng), u(rng), u(rng)),
                                                 b = apex + Vector3d(u(rng), u(rng), u(rng));
    const double scale = std::pow(10.0, -3 - trial % 14);
    const Vector3d p = apex + scale * Vector3d(u(rng), u(rng), u(rng)),
                   q = apex + scale * Vector3d(u(rng), u(rng), u(rng));
    ASSERT_EQ(sh::segment_crosses_wedge(p, q, apex, a, b), crosses_wedge_exact(p, q, apex, a, b))
        << trial;
  }
}

TEST(ShellPinch, CraterRoundtripsEveryInputVertex) {
  // Unbeveled: the rim vertices 0 and 5 are pinch points, the rim edge between them is split.
  // Beveled (what the curved mesher uses): 0 and 5 stay pinch points of the refined surface.
  for (const Case& c : {plain_shell(crater()), beveled_shell(crater())}) {
    EXPECT_EQ(c.singular, 2);
    EXPECT_LE(roundtrip_every_vertex(c), 1e-9);
    EXPECT_GT(check_near_pinch_corners(c), 0);
    const sh::ShellVerification v = sh::verify_shell(c.shell, c.surface);
    EXPECT_EQ(v.roundtrip_failures, 0);
    EXPECT_LE(v.roundtrip_max_error_rel, 1e-9);
  }
}

TEST(ShellPinch, NeedleTipsRoundtrip) {
  // A regular needle and random ones (fixed seed), each with its tip as the only singular vertex.
  std::mt19937 rng(20240917);
  std::uniform_int_distribution<int> sides(5, 9);
  std::uniform_real_distribution<double> radius(0.003, 0.007);
  for (int trial = 0; trial < 9; ++trial) {
    const SurfaceMesh s = trial == 0 ? needle(7, 0.008) : needle(sides(rng), radius(rng), &rng);
    const Case c = plain_shell(s);
    ASSERT_EQ(c.singular, 1) << trial;
    ASSERT_TRUE(pinched(c.shell, 0)) << trial;
    EXPECT_LE(roundtrip_every_vertex(c), 1e-9) << trial;
    EXPECT_GT(check_near_pinch_corners(c), 0);
    const sh::ShellVerification v = sh::verify_shell(c.shell, c.surface);
    EXPECT_TRUE(v.valid()) << trial << ": " << v.non_positive_faces << " "
                           << v.intersecting_input_faces << " " << v.non_section_faces << " "
                           << v.roundtrip_failures;
    EXPECT_LE(v.roundtrip_max_error_rel, 1e-9);
  }
}

TEST(ShellPinch, ProjectionOntoASurfaceMissingThePinchPoint) {
  // P onto another surface: the fiber at the pinch corner is the pinch point alone, so a surface
  // through it within rounding gets its closest point, a surface passing 1e-3 below gets none.
  const SurfaceMesh s = needle(7, 0.008);
  const Case c = plain_shell(s);
  ASSERT_TRUE(pinched(c.shell, 0));
  int face = -1, corner = -1;
  for (int f = 0; f < c.shell.F.rows() && face < 0; ++f) {
    const Eigen::Vector3i F = c.shell.F.row(f);
    for (int k = 0; k < 3; ++k)
      if (F[(sh::min_rotation(F) + k) % 3] == 0) face = f, corner = k;
  }
  ASSERT_GE(face, 0);
  const sh::PrismPoint tip{face, corner == 1 ? 1.0 : 0.0, corner == 2 ? 1.0 : 0.0, 0.0};
  SurfaceMesh rounded = s, below = s;
  rounded.V(0, 2) = std::nextafter(1.0, 0.0);
  below.V(0, 2) = 1.0 - 1e-3;
  const auto near = sh::ShellProjection(c.shell, rounded).project(tip);
  ASSERT_TRUE(near.has_value());
  EXPECT_TRUE(near->position == Vector3d(rounded.V.row(0)));
  EXPECT_FALSE(sh::ShellProjection(c.shell, below).project(tip).has_value());
  // On the needle itself: the tip, in the face of smallest id around it.
  const auto exact = sh::ShellProjection(c.shell, s).project(tip);
  ASSERT_TRUE(exact.has_value());
  EXPECT_EQ(exact->face, 0);
  EXPECT_TRUE(exact->position == Vector3d(s.V.row(0)));
}

TEST(ShellPinch, FacesWithThreeSingularCornersAreSplitUntilEachPrismHasOne) {
  // Issue 21: a knife-edged disc (rim half angle 0.4°, below the 0.57° of the singularity
  // tolerance: every rim vertex singular) with 6 rim slivers, each a face whose three corners are
  // rim vertices. Before: build_shell stopped with "face N has three singular vertices". Now the
  // edges between singular vertices are split until no prism has two singular corners.
  const SurfaceMesh s = curvefem::make_adversarial("knife_disc_slivers");
  const sh::ExtrusionDirections d = sh::extrusion_directions(s.V, s.F);
  int three = 0;
  for (int f = 0; f < s.F.rows(); ++f)
    three += d.singular[std::size_t(s.F(f, 0))] && d.singular[std::size_t(s.F(f, 1))] &&
             d.singular[std::size_t(s.F(f, 2))];
  EXPECT_EQ(three, 6);
  EXPECT_EQ(d.singular_count, 64);  // the rim
  // The plain shell is positive and separated; 8 of its prisms miss the section condition there,
  // which the bevel (what the curved mesher builds) restores.
  const Case plain = plain_shell(s);
  const sh::ShellVerification pv = sh::verify_shell(plain.shell, plain.surface);
  EXPECT_TRUE(pv.positive() && pv.separated());
  for (const Case& c : {beveled_shell(s)}) {
    EXPECT_EQ(c.singular, 64);
    for (int f = 0; f < c.shell.F.rows(); ++f) {
      int n = 0;
      for (int k = 0; k < 3; ++k) n += c.shell.singular[std::size_t(c.shell.F(f, k))];
      EXPECT_LE(n, 1) << "shell face " << f;
    }
    const sh::ShellVerification v = sh::verify_shell(c.shell, c.surface);
    EXPECT_TRUE(v.valid()) << v.non_positive_faces << " " << v.intersecting_input_faces << " "
                           << v.non_section_faces << " " << v.roundtrip_failures;
    EXPECT_LE(roundtrip_every_vertex(c), 1e-9);
  }
}
