// The predicates of the prismatic shell: the per-vertex extrusion direction (the QP of the
// "most visible normal"), exact prism positivity (the 12 tets of the 3-tet splits) and the
// section-contact predicates (triangle vs open tet / open coplanar facet) against brute force.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/shell/extrusion_direction.hpp"
#include "meshing/shell/prism_positivity.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace sh = curvefem::meshing::shell;
using Eigen::Vector3d;

namespace {

Vector3d face_normal(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int f) {
  const Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
  return (b - a).cross(c - a).normalized();
}

Vector3d random_unit(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Vector3d v;
  do v = Vector3d(g(rng), g(rng), g(rng));
  while (v.norm() < 1e-3);
  return v.normalized();
}

// `count` unit normals within `half_angle` of `axis`.
std::vector<Vector3d> random_cone(std::mt19937& rng, const Vector3d& axis, double half_angle,
                                  int count) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  std::vector<Vector3d> n;
  for (int i = 0; i < count; ++i) {
    const double theta = half_angle * std::sqrt(u(rng)), phi = 2 * M_PI * u(rng);
    n.push_back(
        (std::cos(theta) * axis + std::sin(theta) * (std::cos(phi) * e1 + std::sin(phi) * e2))
            .normalized());
  }
  return n;
}

}  // namespace

// ---------------------------------------------------------------- extrusion directions (QP)

TEST(ExtrusionDirection, FlatPatchGivesTheNormal) {
  Vector3d d;
  ASSERT_TRUE(sh::most_visible_direction({Vector3d::UnitZ(), Vector3d::UnitZ(), Vector3d::UnitZ()},
                                         1e-2, d));
  EXPECT_EQ(d, Vector3d::UnitZ());
  const Vector3d n = Vector3d(1, 2, 2).normalized();
  ASSERT_TRUE(sh::most_visible_direction({n, n, n, n, n}, 1e-2, d));
  EXPECT_LE((d - n).norm(), 4e-16);

  // A planar open grid: every vertex (corners, border, interior) gets exactly +z.
  const int k = 4;
  Eigen::MatrixXd V((k + 1) * (k + 1), 3);
  Eigen::MatrixXi F(2 * k * k, 3);
  for (int i = 0; i <= k; ++i)
    for (int j = 0; j <= k; ++j) V.row(i * (k + 1) + j) << 0.3 * j, 0.7 * i, 2.0;
  for (int i = 0, f = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      const int a = i * (k + 1) + j, b = a + 1, c = a + k + 2, e = a + k + 1;
      F.row(f++) << a, b, c;
      F.row(f++) << a, c, e;
    }
  const sh::ExtrusionDirections dirs = sh::extrusion_directions(V, F);
  EXPECT_EQ(dirs.singular_count, 0);
  for (int v = 0; v < V.rows(); ++v) EXPECT_EQ(Vector3d(dirs.N.row(v)), Vector3d::UnitZ()) << v;
}

TEST(ExtrusionDirection, CubeCornerGivesTheDiagonal) {
  Vector3d d;
  ASSERT_TRUE(sh::most_visible_direction(
      {Vector3d::UnitX(), Vector3d::UnitY(), Vector3d::UnitY(), Vector3d::UnitZ()}, 1e-2, d));
  EXPECT_LE((d - Vector3d(1, 1, 1) / std::sqrt(3.0)).norm(), 1e-15);
  ASSERT_TRUE(sh::detail::most_visible_direction_exact(
      {Vector3d::UnitX(), Vector3d::UnitY(), Vector3d::UnitZ()}, 1e-2, d));
  EXPECT_LE((d - Vector3d(1, 1, 1) / std::sqrt(3.0)).norm(), 1e-15);
  // A cube edge: the bisector.
  ASSERT_TRUE(sh::most_visible_direction({Vector3d::UnitX(), -Vector3d::UnitY()}, 1e-2, d));
  EXPECT_LE((d - Vector3d(1, -1, 0) / std::sqrt(2.0)).norm(), 1e-15);
}

TEST(ExtrusionDirection, SingularVertices) {
  Vector3d d(1, 1, 1);
  // Normals ±z: infeasible, for both solvers.
  EXPECT_FALSE(sh::most_visible_direction({Vector3d::UnitZ(), -Vector3d::UnitZ()}, 1e-2, d));
  EXPECT_EQ(d, Vector3d::Zero());
  EXPECT_FALSE(
      sh::detail::most_visible_direction_exact({Vector3d::UnitZ(), -Vector3d::UnitZ()}, 1e-2, d));
  EXPECT_EQ(
      sh::detail::most_visible_direction_fast({Vector3d::UnitZ(), -Vector3d::UnitZ()}, 1e-2, d),
      sh::detail::FastOutcome::singular);
  // The origin inside the hull of four normals (a saddle-like fan).
  const std::vector<Vector3d> saddle = {
      Vector3d(1, 0, 0.2).normalized(), Vector3d(0, 1, -0.2).normalized(),
      Vector3d(-1, 0, 0.2).normalized(), Vector3d(0, -1, -0.2).normalized()};
  EXPECT_FALSE(sh::most_visible_direction(saddle, 1e-2, d));
  EXPECT_FALSE(sh::detail::most_visible_direction_exact(saddle, 1e-2, d));
  // Feasible but too flat: two faces at 89.7° from the optimum (cos = 0.005 < 0.01); at 88.9°
  // (cos = 0.02) the vertex is regular with direction +z.
  for (double c : {0.005, 0.02}) {
    const double s = std::sqrt(1 - c * c);
    const std::vector<Vector3d> wedge = {Vector3d(s, 0, c), Vector3d(-s, 0, c)};
    EXPECT_EQ(sh::most_visible_direction(wedge, 1e-2, d), c > 0.01) << c;
    EXPECT_EQ(sh::detail::most_visible_direction_exact(wedge, 1e-2, d), c > 0.01) << c;
    if (c > 0.01) {
      EXPECT_LE((d - Vector3d::UnitZ()).norm(), 1e-15);
    }
  }
  EXPECT_FALSE(sh::most_visible_direction({}, 1e-2, d));
}

TEST(ExtrusionDirection, FastPathMatchesExactSolver) {
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int fast_direction = 0, fast_singular = 0, undecided = 0, compared = 0;
  double worst = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vector3d axis = random_unit(rng);
    // Mostly feasible cones (half-angle up to 88°), some wider than a hemisphere.
    const double half_angle = (trial % 5 == 4 ? 1.3 + 1.2 * u(rng) : 1.54 * u(rng));
    const int count = 3 + static_cast<int>(u(rng) * 10);
    std::vector<Vector3d> n = random_cone(rng, axis, half_angle, count);
    if (trial % 6 == 1) {  // 2–3 tight clusters, as at creases of CAD tessellations
      std::vector<Vector3d> centers(n.begin(), n.begin() + 2 + trial % 4 / 3);
      n.clear();
      for (int i = 0; i < count; ++i) {
        const double spread = std::pow(10.0, -6 - 8 * u(rng));
        n.push_back((centers[i % centers.size()] + spread * random_unit(rng)).normalized());
      }
    }
    if (trial % 4 == 3) {  // near-duplicates, as on flat or faceted regions
      const int copies = 1 + static_cast<int>(u(rng) * 3);
      for (int c = 0; c < copies; ++c) {
        const Vector3d base = n[static_cast<int>(u(rng) * n.size())];
        const double scale = std::pow(10.0, -4 - 12 * u(rng));
        n.push_back((base + scale * random_unit(rng)).normalized());
      }
    }
    Vector3d exact, fast, combined;
    const bool exact_regular = sh::detail::most_visible_direction_exact(n, 1e-2, exact);
    const auto outcome = sh::detail::most_visible_direction_fast(n, 1e-2, fast);
    const bool regular = sh::most_visible_direction(n, 1e-2, combined);
    ASSERT_EQ(regular, exact_regular) << trial;
    if (regular) {
      ASSERT_LE((combined - exact).norm(), 1e-12) << trial;
      ASSERT_NEAR(combined.norm(), 1.0, 1e-15);
      for (const Vector3d& nf : n) ASSERT_GE(nf.dot(combined), 1e-2);
    }
    switch (outcome) {
      case sh::detail::FastOutcome::direction:
        ++fast_direction;
        ASSERT_TRUE(exact_regular) << trial;
        worst = std::max(worst, (fast - exact).norm());
        ASSERT_LE((fast - exact).norm(), 1e-12) << trial;
        ++compared;
        break;
      case sh::detail::FastOutcome::singular:
        ++fast_singular;
        ASSERT_FALSE(exact_regular) << trial;
        break;
      case sh::detail::FastOutcome::undecided:
        ++undecided;
        break;
    }
  }
  // The fast path decides nearly everything itself; both kinds of vertices occur.
  EXPECT_GE(fast_direction, 1800);
  EXPECT_GE(fast_singular, 100);
  EXPECT_LE(undecided, 40);  // near-singular vertices (small ‖y‖) go to the exact solver
  EXPECT_LE(worst, 1e-12);
  std::printf("fast: %d directions, %d singular, %d undecided; worst |fast - exact| = %.2e\n",
              fast_direction, fast_singular, undecided, worst);
}

TEST(ExtrusionDirection, CreaseClustersMatchExactSolver) {
  // Vertices 492 and 495 of tr12j_occt.obj: two clusters of normals ~4e-8 apart, where the
  // optimum lies on a sliver face; an early fast path got these wrong by 1e-8.
  const std::vector<std::vector<Vector3d>> cases = {
      {{0, -0.99862760738802425, 0.052372719639805609},
       {0, -0.99862760540834616, 0.052372757387716379},
       {0, -0.99862760540834616, 0.052372757387716379},
       {-0.35792204330537619, -0.93246999623787719, 0.048903139288165115},
       {-0.35792207478610777, -0.93246998603589126, 0.048903103409012397}},
      {{0, -0.99862760540834616, 0.052372757387716379},
       {0, -0.99862760738802425, 0.052372719639805609},
       {0, -0.99862760738802425, 0.052372719639805609},
       {-0.38829799262190368, -0.92026915939137155, 0.048263269666467781},
       {-0.38826382721870023, -0.92028297902101541, 0.048274620637479677},
       {-0.38824981614644749, -0.92028943154069731, 0.048264297951487838}}};
  for (const auto& n : cases) {
    Vector3d exact, fast, combined;
    ASSERT_TRUE(sh::detail::most_visible_direction_exact(n, 1e-2, exact));
    ASSERT_TRUE(sh::most_visible_direction(n, 1e-2, combined));
    EXPECT_LE((combined - exact).norm(), 1e-12);
    if (sh::detail::most_visible_direction_fast(n, 1e-2, fast) ==
        sh::detail::FastOutcome::direction) {
      EXPECT_LE((fast - exact).norm(), 1e-12);
    }
  }
}

TEST(ExtrusionDirection, IcosphereIsRegularAndRadial) {
  const curvefem::SurfaceMesh sphere = curvefem::make_icosphere(3);
  const sh::ExtrusionDirections dirs = sh::extrusion_directions(sphere.V, sphere.F);
  ASSERT_EQ(dirs.N.rows(), sphere.V.rows());
  EXPECT_EQ(dirs.singular_count, 0);
  double min_dot = 1;
  for (int f = 0; f < sphere.F.rows(); ++f) {
    const Vector3d n = face_normal(sphere.V, sphere.F, f);
    for (int c = 0; c < 3; ++c) min_dot = std::min(min_dot, n.dot(dirs.N.row(sphere.F(f, c))));
  }
  EXPECT_GE(min_dot, 0.9);
  for (int v = 0; v < sphere.V.rows(); ++v) {
    EXPECT_EQ(dirs.singular[v], 0);
    EXPECT_NEAR(dirs.N.row(v).norm(), 1.0, 1e-15);
    EXPECT_LE((dirs.N.row(v) - sphere.V.row(v).normalized()).norm(), 1e-2) << v;
  }
}

TEST(ExtrusionDirection, BoxCornersEdgesAndFaces) {
  const Vector3d lo(-1, -2, -3), hi(1, 2, 3);
  const curvefem::SurfaceMesh box = curvefem::make_box(lo, hi, 2);
  const sh::ExtrusionDirections dirs = sh::extrusion_directions(box.V, box.F);
  EXPECT_EQ(dirs.singular_count, 0);
  int corners = 0;
  for (int v = 0; v < box.V.rows(); ++v) {
    Vector3d expected = Vector3d::Zero();
    for (int c = 0; c < 3; ++c) {
      if (box.V(v, c) == lo[c]) expected[c] = -1;
      if (box.V(v, c) == hi[c]) expected[c] = 1;
    }
    corners += expected.cwiseAbs().sum() == 3 ? 1 : 0;
    expected.normalize();  // corner (±1,±1,±1)/√3, edge (±1,±1,0)/√2, face ±axis
    EXPECT_LE((dirs.N.row(v).transpose() - expected).norm(), 1e-15) << v;
  }
  EXPECT_EQ(corners, 8);
}

TEST(ExtrusionDirection, DegenerateUnreferencedAndInvalidInput) {
  // Two faces; the second is degenerate (collinear), vertex 4 is unreferenced.
  Eigen::MatrixXd V(5, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0, 7, 7, 7;
  Eigen::MatrixXi F(2, 3);
  F << 0, 1, 2, 0, 3, 1;
  const sh::ExtrusionDirections dirs = sh::extrusion_directions(V, F);
  EXPECT_EQ(dirs.singular_count, 3);  // 0, 1, 3 touch the degenerate face
  EXPECT_EQ(dirs.singular, (std::vector<char>{1, 1, 0, 1, 0}));
  EXPECT_EQ(Vector3d(dirs.N.row(2)), Vector3d::UnitZ());
  EXPECT_EQ(Vector3d(dirs.N.row(4)), Vector3d::Zero());
  EXPECT_EQ(Vector3d(dirs.N.row(0)), Vector3d::Zero());
  F(1, 2) = 5;
  EXPECT_THROW(sh::extrusion_directions(V, F), curvefem::InputError);
}

TEST(ExtrusionDirection, IdenticalAtOneAndTwoThreads) {
  curvefem::SurfaceMesh mesh = curvefem::make_icosphere(3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  for (int v = 0; v < mesh.V.rows(); ++v)
    for (int c = 0; c < 3; ++c) mesh.V(v, c) += u(rng);
  sh::ExtrusionDirections one, two;
  tbb::task_arena(1).execute([&] { one = sh::extrusion_directions(mesh.V, mesh.F); });
  tbb::task_arena(2).execute([&] { two = sh::extrusion_directions(mesh.V, mesh.F); });
  EXPECT_EQ(one.singular, two.singular);
  EXPECT_EQ(one.singular_count, two.singular_count);
  EXPECT_TRUE(one.N == two.N);
}

// ---------------------------------------------------------------- prism positivity

namespace {

using Tet = std::array<int, 4>;

// The right prism: base (0,0,0), (1,0,0), (0,1,0), top = base + (0,0,1).
std::array<Vector3d, 6> right_prism() {
  return {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0),
          Vector3d(0, 0, 1), Vector3d(1, 0, 1), Vector3d(0, 1, 1)};
}

double orient(const std::array<Vector3d, 6>& p, const Tet& t) {
  return (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).dot(p[t[3]] - p[t[0]]);
}

// Oriented tet as (sorted corners, parity of the sorting permutation).
std::pair<Tet, int> oriented_key(Tet t) {
  int parity = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j + 1 < 4 - i; ++j)
      if (t[j] > t[j + 1]) {
        std::swap(t[j], t[j + 1]);
        parity ^= 1;
      }
  return {t, parity};
}

struct SplitEnumeration {
  std::set<std::pair<Tet, int>> tets;  // union over the valid splits, oriented positively
  int valid_choices = 0, cyclic_choices = 0;
  std::vector<std::array<int, 3>> cyclic;  // diagonal choices without a split
};

// Brute force: each side quad gets one of its two diagonals; a split is 3 tets on the 6 corners,
// non-degenerate on the right prism, whose faces are exactly the 8 boundary triangles (once each)
// plus interior triangles shared by two tets, and whose volumes add up to the volume of a
// (non-right) frustum-shaped prism.
SplitEnumeration enumerate_splits() {
  const std::array<std::array<int, 4>, 3> quads = {{{0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}}};
  const auto right = right_prism();
  std::array<Vector3d, 6> frustum;  // top = 0.6 · base + offset: planar side quads, convex
  for (int i = 0; i < 3; ++i) {
    frustum[i] = right[i];
    frustum[i + 3] = 0.6 * right[i] + Vector3d(0.1, 0.15, 1.3);
  }
  const double a0 = 0.5, a1 = 0.5 * 0.36, h = 1.3;
  const double frustum_volume = h / 3 * (a0 + a1 + std::sqrt(a0 * a1));

  std::vector<Tet> candidates;  // 4-subsets that are not degenerate on the right prism
  for (int a = 0; a < 6; ++a)
    for (int b = a + 1; b < 6; ++b)
      for (int c = b + 1; c < 6; ++c)
        for (int d = c + 1; d < 6; ++d) {
          Tet t{a, b, c, d};
          if (std::abs(orient(right, t)) < 1e-12) continue;
          if (orient(right, t) < 0) std::swap(t[2], t[3]);
          candidates.push_back(t);
        }
  EXPECT_EQ(candidates.size(), 12u);  // 15 minus the 3 side quads

  SplitEnumeration out;
  for (int choice = 0; choice < 8; ++choice) {
    std::map<std::array<int, 3>, int> boundary;
    auto tri = [](int a, int b, int c) {
      std::array<int, 3> t{a, b, c};
      std::sort(t.begin(), t.end());
      return t;
    };
    boundary[tri(0, 1, 2)] = 0;
    boundary[tri(3, 4, 5)] = 0;
    std::array<int, 3> diagonal_start{};
    for (int q = 0; q < 3; ++q) {
      const auto& Q = quads[q];
      if (choice & (1 << q)) {  // diagonal Q0–Q2
        boundary[tri(Q[0], Q[1], Q[2])] = 0;
        boundary[tri(Q[0], Q[2], Q[3])] = 0;
        diagonal_start[q] = Q[0];
      } else {  // diagonal Q1–Q3
        boundary[tri(Q[0], Q[1], Q[3])] = 0;
        boundary[tri(Q[1], Q[2], Q[3])] = 0;
        diagonal_start[q] = Q[1];
      }
    }
    int splits = 0;
    const int m = static_cast<int>(candidates.size());
    for (int i = 0; i < m; ++i)
      for (int j = i + 1; j < m; ++j)
        for (int k = j + 1; k < m; ++k) {
          std::map<std::array<int, 3>, int> faces;
          double volume = 0;
          for (int t : {i, j, k}) {
            const Tet& T = candidates[t];
            for (int skip = 0; skip < 4; ++skip) {
              std::array<int, 3> f{};
              for (int c = 0, n = 0; c < 4; ++c)
                if (c != skip) f[n++] = T[c];
              std::sort(f.begin(), f.end());
              ++faces[f];
            }
            volume += orient(frustum, T) / 6;
          }
          bool ok = true;
          for (const auto& [f, count] : faces) {
            const bool on_boundary = boundary.count(f) > 0;
            if ((on_boundary && count != 1) || (!on_boundary && count != 2)) ok = false;
          }
          for (const auto& [f, unused] : boundary)
            if (!faces.count(f)) ok = false;
          if (!ok) continue;
          EXPECT_NEAR(volume, frustum_volume, 1e-12);
          ++splits;
          for (int t : {i, j, k}) out.tets.insert(oriented_key(candidates[t]));
        }
    EXPECT_LE(splits, 1) << choice;
    if (splits == 1) {
      ++out.valid_choices;
    } else {
      ++out.cyclic_choices;
      out.cyclic.push_back(diagonal_start);
    }
  }
  return out;
}

}  // namespace

TEST(PrismPositivity, TuplesArePositiveOnTheRightPrismAndGroupedByPillar) {
  const auto& tets = sh::prism_tets();
  const auto right = right_prism();
  std::set<std::pair<Tet, int>> keys;
  for (int k = 0; k < 12; ++k) {
    EXPECT_DOUBLE_EQ(orient(right, tets[k]), 1.0) << k;  // 6 · (volume 1/6)
    const int pillar = k / 4;
    EXPECT_NE(std::count(tets[k].begin(), tets[k].end(), pillar), 0) << k;
    EXPECT_NE(std::count(tets[k].begin(), tets[k].end(), pillar + 3), 0) << k;
    keys.insert(oriented_key(tets[k]));
  }
  EXPECT_EQ(keys.size(), 12u);
  EXPECT_TRUE(sh::prism_positive(right));
  std::array<Vector3d, 6> mirrored = right;  // z → −z: every tet negative
  for (auto& p : mirrored) p.z() = -p.z();
  EXPECT_FALSE(sh::prism_positive(mirrored));
}

TEST(PrismPositivity, TuplesAreTheTetsOfTheValidSplits) {
  const SplitEnumeration splits = enumerate_splits();
  EXPECT_EQ(splits.valid_choices, 6);
  EXPECT_EQ(splits.cyclic_choices, 2);
  // The two cyclic choices: diagonals 0–4, 1–5, 2–3 and 1–3, 2–4, 0–5.
  std::set<std::array<int, 3>> cyclic(splits.cyclic.begin(), splits.cyclic.end());
  EXPECT_EQ(cyclic, (std::set<std::array<int, 3>>{{0, 1, 2}, {1, 2, 0}}));
  std::set<std::pair<Tet, int>> listed;
  for (const Tet& t : sh::prism_tets()) listed.insert(oriented_key(t));
  EXPECT_EQ(splits.tets.size(), 12u);
  EXPECT_EQ(listed, splits.tets);
}

TEST(PrismPositivity, RandomPrismsMatchAllSplitsPositive) {
  const SplitEnumeration splits = enumerate_splits();
  std::vector<Tet> tets;
  for (const auto& [t, parity] : splits.tets) {
    Tet s = t;
    if (parity) std::swap(s[2], s[3]);
    tets.push_back(s);
  }
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int positive = 0, negative = 0, skipped = 0;
  const auto right = right_prism();
  for (int trial = 0; trial < 5000; ++trial) {
    std::array<Vector3d, 6> p;
    for (int i = 0; i < 6; ++i) {
      const double noise = i < 3 ? 0.25 : 0.6;
      p[i] = right[i] + noise * Vector3d(u(rng), u(rng), u(rng));
    }
    bool expected = true, degenerate = false;
    for (const Tet& t : tets) {
      const double o = orient(p, t);
      if (std::abs(o) < 1e-6) degenerate = true;
      if (o <= 0) expected = false;
    }
    if (degenerate) {
      ++skipped;
      continue;
    }
    ASSERT_EQ(sh::prism_positive(p), expected) << trial;
    (expected ? positive : negative) += 1;
  }
  EXPECT_GE(positive, 500);
  EXPECT_GE(negative, 500);
  EXPECT_LE(skipped, 50);
}

TEST(PrismPositivity, SingularPillarSkipsItsBlock) {
  std::array<Vector3d, 6> p = right_prism();
  p[3] = p[0];  // pillar 0 has zero length
  EXPECT_TRUE(sh::prism_positive(p, {true, false, false}));
  EXPECT_FALSE(sh::prism_positive(p));  // block 0 is degenerate
  for (int k = 4; k < 12; ++k) EXPECT_GT(orient(p, sh::prism_tets()[k]), 0.0) << k;
  for (int k = 0; k < 4; ++k) EXPECT_EQ(orient(p, sh::prism_tets()[k]), 0.0) << k;
  p[4].z() = -0.5;  // the rest must still be positive
  EXPECT_FALSE(sh::prism_positive(p, {true, false, false}));
}

TEST(PrismPositivity, ShellFaceChecksBothHalves) {
  std::array<Vector3d, 3> base, mid, top;
  const auto right = right_prism();
  for (int i = 0; i < 3; ++i) {
    base[i] = right[i];
    mid[i] = right[i] + Vector3d(0, 0, 1);
    top[i] = right[i] + Vector3d(0, 0, 2);
  }
  EXPECT_TRUE(sh::shell_face_positive(base, mid, top));
  auto low = mid;
  low[0].z() = -0.5;  // mid below the base at corner 0: the lower half inverts
  EXPECT_FALSE(sh::shell_face_positive(base, low, top));
  auto high = mid;
  high[1].z() = 2.5;  // mid above the top at corner 1: the upper half inverts
  EXPECT_FALSE(sh::shell_face_positive(base, high, top));
  // A singular vertex: base = mid = top at corner 2.
  base[2] = mid[2];
  top[2] = mid[2];
  EXPECT_TRUE(sh::shell_face_positive(base, mid, top, {false, false, true}));
  EXPECT_FALSE(sh::shell_face_positive(base, mid, top));
}

// ---------------------------------------------------------------- section contact (I2)
//
// Brute force, independent of the separating-axis code: clip the triangle by the closed
// half-spaces of the tet (or, for a coplanar facet, by the facet's in-plane edge half-spaces)
// in exact rational arithmetic. The clipped polygon P meets the open tet iff the average of its
// vertices lies strictly inside (it lies in relint P, and a convex P ⊂ T meeting int T cannot
// have a relative-interior point on a supporting plane of T without lying in that plane).

namespace {

using Q = CGAL::Exact_rational;
using QV = std::array<Q, 3>;

QV qv(const Vector3d& p) { return {Q(p.x()), Q(p.y()), Q(p.z())}; }
QV sub(const QV& a, const QV& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
QV cross(const QV& a, const QV& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Q dot(const QV& a, const QV& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Half-space {x : n · (x − o) ≥ 0}.
struct HalfSpace {
  QV n, o;
  Q eval(const QV& x) const { return dot(n, sub(x, o)); }
};

std::vector<QV> clip(const std::vector<QV>& poly, const HalfSpace& h) {
  std::vector<QV> out;
  const std::size_t m = poly.size();
  for (std::size_t i = 0; i < m; ++i) {
    const QV &a = poly[i], &b = poly[(i + 1) % m];
    const Q fa = h.eval(a), fb = h.eval(b);
    if (fa >= 0) out.push_back(a);
    if ((fa > 0 && fb < 0) || (fa < 0 && fb > 0)) {
      const Q t = fa / (fa - fb);
      out.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])});
    }
  }
  return out;
}

// Clips the triangle by the half-spaces; true iff the result meets their common open interior.
bool brute_meets_open(const std::array<Vector3d, 3>& tri, const std::vector<HalfSpace>& hs) {
  std::vector<QV> poly{qv(tri[0]), qv(tri[1]), qv(tri[2])};
  for (const HalfSpace& h : hs) {
    poly = clip(poly, h);
    if (poly.empty()) return false;
  }
  QV c{Q(0), Q(0), Q(0)};
  for (const QV& p : poly)
    for (int k = 0; k < 3; ++k) c[k] += p[k];
  for (int k = 0; k < 3; ++k) c[k] /= Q(int(poly.size()));
  for (const HalfSpace& h : hs)
    if (!(h.eval(c) > 0)) return false;
  return true;
}

bool brute_closed_contact(const std::array<Vector3d, 3>& tri, const std::vector<HalfSpace>& hs) {
  std::vector<QV> poly{qv(tri[0]), qv(tri[1]), qv(tri[2])};
  for (const HalfSpace& h : hs) {
    poly = clip(poly, h);
    if (poly.empty()) return false;
  }
  return true;
}

Q qdet(const QV& a, const QV& b, const QV& c, const QV& d) {
  return dot(cross(sub(b, a), sub(c, a)), sub(d, a));
}

std::vector<HalfSpace> tet_halfspaces(const std::array<Vector3d, 4>& T) {
  static const int f[4][4] = {{1, 2, 3, 0}, {0, 2, 3, 1}, {0, 1, 3, 2}, {0, 1, 2, 3}};
  std::vector<HalfSpace> hs;
  for (const auto& k : f) {
    const QV a = qv(T[k[0]]), b = qv(T[k[1]]), c = qv(T[k[2]]), d = qv(T[k[3]]);
    QV n = cross(sub(b, a), sub(c, a));
    if (dot(n, sub(d, a)) < 0) n = {-n[0], -n[1], -n[2]};
    hs.push_back({n, a});
  }
  return hs;
}

bool brute_open_tet(const std::array<Vector3d, 3>& tri, const std::array<Vector3d, 4>& T) {
  return brute_meets_open(tri, tet_halfspaces(T));
}

bool brute_open_facet(const std::array<Vector3d, 3>& tri, const std::array<Vector3d, 3>& F) {
  const QV a = qv(F[0]), b = qv(F[1]), c = qv(F[2]);
  const QV n = cross(sub(b, a), sub(c, a));
  for (const Vector3d& p : tri)
    if (dot(n, sub(qv(p), a)) != 0) return false;
  std::vector<HalfSpace> hs;
  const std::array<QV, 3> f{a, b, c};
  for (int i = 0; i < 3; ++i) {
    const QV &p = f[i], &q = f[(i + 1) % 3], &r = f[(i + 2) % 3];
    QV m = cross(sub(q, p), n);
    if (dot(m, sub(r, p)) < 0) m = {-m[0], -m[1], -m[2]};
    hs.push_back({m, p});
  }
  return brute_meets_open(tri, hs);
}

bool non_degenerate(const std::array<Vector3d, 4>& T) {
  return qdet(qv(T[0]), qv(T[1]), qv(T[2]), qv(T[3])) != 0;
}

// Outcome counts of one comparison run.
struct ContactCounts {
  int open = 0, facet_only = 0, closed_only = 0, apart = 0;
};

// Compares the three predicates with brute force on (tri, T); T non-degenerate.
void compare_with_brute_force(const std::array<Vector3d, 3>& tri, const std::array<Vector3d, 4>& T,
                              ContactCounts& counts, const std::string& where) {
  const bool open = brute_open_tet(tri, T);
  ASSERT_EQ(sh::triangle_meets_open_tet(tri, T), open) << where;
  static const int f[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  bool facet = false;
  for (const auto& k : f) {
    const std::array<Vector3d, 3> F{T[k[0]], T[k[1]], T[k[2]]};
    const bool b = brute_open_facet(tri, F);
    ASSERT_EQ(sh::triangle_meets_open_facet(tri, F), b) << where;
    facet = facet || b;
  }
  ASSERT_EQ(sh::triangle_section_contact(tri, T), open || facet) << where;
  if (open)
    ++counts.open;
  else if (facet)
    ++counts.facet_only;
  else if (brute_closed_contact(tri, tet_halfspaces(T)))
    ++counts.closed_only;
  else
    ++counts.apart;
}

std::string counts_text(const ContactCounts& c) {
  return "open " + std::to_string(c.open) + ", facet only " + std::to_string(c.facet_only) +
         ", closed only " + std::to_string(c.closed_only) + ", apart " + std::to_string(c.apart);
}

std::array<Vector3d, 4> random_integer_tet(std::mt19937& rng, int range) {
  std::uniform_int_distribution<int> c(0, range);
  std::array<Vector3d, 4> T;
  do
    for (auto& p : T) p = Vector3d(c(rng), c(rng), c(rng));
  while (!non_degenerate(T));
  return T;
}

}  // namespace

TEST(SectionContact, SmallIntegerConfigurationsMatchBruteForce) {
  // Coordinates in {0..3}: shared vertices, shared edges, coplanar faces and parallel edges are
  // frequent.
  std::mt19937 rng(2024);
  std::uniform_int_distribution<int> c(0, 3);
  ContactCounts counts;
  for (int trial = 0; trial < 3000; ++trial) {
    const auto T = random_integer_tet(rng, 3);
    std::array<Vector3d, 3> tri;
    for (auto& p : tri) p = Vector3d(c(rng), c(rng), c(rng));
    compare_with_brute_force(tri, T, counts, "trial " + std::to_string(trial));
  }
  RecordProperty("counts", counts_text(counts));
  EXPECT_GE(counts.open, 400);
  EXPECT_GE(counts.facet_only, 10);
  EXPECT_GE(counts.closed_only, 200);
  EXPECT_GE(counts.apart, 200);
}

TEST(SectionContact, AdversarialTouchingConfigurationsMatchBruteForce) {
  // Triangle corners drawn from a pool built on the tet: its corners, edge midpoints, facet
  // centroids, its centroid, and points outside (corners pushed away from the centroid, edge
  // extensions, corners reflected through facets). Coordinates are multiples of 1/6 of integers,
  // exact in double.
  std::mt19937 rng(7);
  ContactCounts counts;
  for (int trial = 0; trial < 1000; ++trial) {
    std::array<Vector3d, 4> T = random_integer_tet(rng, 4);
    for (auto& p : T) p *= 6.0;
    std::vector<Vector3d> pool(T.begin(), T.end());
    const Vector3d g = 0.25 * (T[0] + T[1] + T[2] + T[3]);
    pool.push_back(g);
    for (int i = 0; i < 4; ++i) {
      pool.push_back(2 * T[i] - g);
      for (int j = i + 1; j < 4; ++j) {
        pool.push_back(0.5 * (T[i] + T[j]));
        pool.push_back(2 * T[j] - T[i]);
        pool.push_back(2 * T[i] - T[j]);
      }
      Vector3d fc = Vector3d::Zero();
      for (int j = 0; j < 4; ++j)
        if (j != i) fc += T[j];
      fc /= 3.0;
      pool.push_back(fc);
      pool.push_back(2 * fc - T[i]);  // the corner reflected through its facet's centroid
      pool.push_back(fc + (fc - g));
    }
    std::uniform_int_distribution<int> pick(0, int(pool.size()) - 1);
    for (int rep = 0; rep < 4; ++rep) {
      std::array<Vector3d, 3> tri{pool[pick(rng)], pool[pick(rng)], pool[pick(rng)]};
      compare_with_brute_force(tri, T, counts,
                               "trial " + std::to_string(trial) + "." + std::to_string(rep));
    }
  }
  RecordProperty("counts", counts_text(counts));
  EXPECT_GE(counts.open, 1000);
  EXPECT_GE(counts.facet_only, 100);
  EXPECT_GE(counts.closed_only, 500);
  EXPECT_GE(counts.apart, 100);
}

TEST(SectionContact, GenericAndNearlyTouchingConfigurationsMatchBruteForce) {
  // Non-integer coordinates, and triangles through a tet corner or along an edge direction
  // perturbed by one ulp-scale offset: exact decisions near contact.
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ContactCounts counts;
  for (int trial = 0; trial < 1500; ++trial) {
    std::array<Vector3d, 4> T;
    do
      for (auto& p : T) p = Vector3d(u(rng), u(rng), u(rng));
    while (!non_degenerate(T));
    std::array<Vector3d, 3> tri;
    for (auto& p : tri) p = Vector3d(u(rng), u(rng), u(rng));
    if (trial % 3 == 1) tri[0] = T[trial % 4];  // through a corner
    if (trial % 3 == 2) {
      // Along an edge, nudged by 1e-17.
      tri[0] = T[0];
      tri[1] = T[0] + 2.0 * (T[1] - T[0]) + Vector3d(1e-17, -1e-17, 0);
    }
    compare_with_brute_force(tri, T, counts, "trial " + std::to_string(trial));
  }
  RecordProperty("counts", counts_text(counts));
  EXPECT_GE(counts.open, 300);
  EXPECT_GE(counts.apart, 150);
}

TEST(SectionContact, DegenerateTetAndTriangle) {
  const std::array<Vector3d, 4> flat{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0),
                                     Vector3d(1, 1, 0)};
  const std::array<Vector3d, 3> through{Vector3d(0.2, 0.2, -1), Vector3d(0.3, 0.2, 1),
                                        Vector3d(0.2, 0.3, 1)};
  EXPECT_FALSE(sh::triangle_meets_open_tet(through, flat));  // no interior
  const std::array<Vector3d, 4> T{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0),
                                  Vector3d(0, 0, 1)};
  // A segment (degenerate triangle) through the interior, and one along an edge.
  const std::array<Vector3d, 3> needle{Vector3d(0.1, 0.1, -1), Vector3d(0.1, 0.1, 2),
                                       Vector3d(0.1, 0.1, 0.5)};
  EXPECT_TRUE(sh::triangle_meets_open_tet(needle, T));
  const std::array<Vector3d, 3> on_edge{Vector3d(-1, 0, 0), Vector3d(2, 0, 0), Vector3d(0.5, 0, 0)};
  EXPECT_FALSE(sh::triangle_meets_open_tet(on_edge, T));
  EXPECT_FALSE(sh::triangle_section_contact(on_edge, T));
  // Both orientations of the tet.
  std::array<Vector3d, 4> mirrored = T;
  std::swap(mirrored[1], mirrored[2]);
  EXPECT_TRUE(sh::triangle_meets_open_tet(needle, mirrored));
  // Exact sign of the normal against a direction.
  const std::array<Vector3d, 3> xy{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
  EXPECT_EQ(sh::normal_dot_sign(xy, Vector3d(5, 5, 1), Vector3d(7, -3, std::nextafter(1.0, 2.0))),
            1);
  EXPECT_EQ(sh::normal_dot_sign(xy, Vector3d(5, 5, 1), Vector3d(7, -3, 1)), 0);
  EXPECT_EQ(sh::normal_dot_sign(xy, Vector3d(0, 0, 1), Vector3d(0, 0, 0.5)), -1);
}

namespace {
// The 6 canonical split tets of a prism over (m0, m1, m2) with pillar directions d and half
// height h (face ids 0, 1, 2: type B); flat tets of zero-length pillars are dropped.
std::vector<std::array<Vector3d, 4>> split(const std::array<Vector3d, 3>& m,
                                           const std::array<Vector3d, 3>& d, double h) {
  const Eigen::Vector3i F(0, 1, 2);
  std::vector<std::array<Vector3d, 4>> tets;
  for (int half = 0; half < 2; ++half)
    for (const auto& tet : sh::split_tets(sh::is_type_a(F))) {
      std::array<Vector3d, 4> c;
      for (int k = 0; k < 4; ++k) {
        const int v = tet[k] % 3;
        const double level = (tet[k] < 3 ? -1.0 : 0.0) + half;
        c[k] = m[v] + level * h * d[v];
      }
      if (non_degenerate(c)) tets.push_back(c);
    }
  return tets;
}
}  // namespace

TEST(SectionContact, SharpEdgeNeighbourTouchesOnlyTheLateralBoundary) {
  // A face of a box (z = 0) next to the wall across its edge on the x axis (y = 0, going down,
  // normal −y). Pillars on the edge bisect the 90° angle; the opposite pillar is +z.
  const std::array<Vector3d, 3> m{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
  const Vector3d bis = Vector3d(0, -1, 1).normalized();
  for (const double h : {0.1, 0.4}) {
    const auto tets = split(m, {bis, bis, Vector3d::UnitZ()}, h);
    ASSERT_EQ(tets.size(), 6u);
    const std::array<Vector3d, 3> own = m;
    const std::array<Vector3d, 3> wall{m[1], m[0], Vector3d(0.5, 0, -1)};
    // A flat continuation touches along the edge only; a steep one (concave, > 45°) enters.
    const std::array<Vector3d, 3> flat{m[1], m[0], Vector3d(0.5, -1, 0)};
    const std::array<Vector3d, 3> steep{m[1], m[0], Vector3d(0.5, -1, 1.5)};
    const std::array<Vector3d, 3> in_side{m[0], m[1], m[1] + 0.5 * h * bis};  // in a side quad
    int wall_touching = 0, own_contact = 0, steep_contact = 0, side_contact = 0;
    for (const auto& T : tets) {
      EXPECT_FALSE(sh::triangle_section_contact(wall, T));  // the old closed test flagged it
      wall_touching += brute_closed_contact(wall, tet_halfspaces(T));
      own_contact += sh::triangle_section_contact(own, T);
      EXPECT_FALSE(sh::triangle_section_contact(flat, T));
      steep_contact += sh::triangle_section_contact(steep, T);
      side_contact += sh::triangle_section_contact(in_side, T);
      EXPECT_FALSE(sh::triangle_meets_open_tet(own, T));  // it lies in the mid triangle
    }
    EXPECT_GE(wall_touching, 2);
    EXPECT_GE(own_contact, 2);    // coplanar with the mid facet of both halves
    EXPECT_GE(steep_contact, 1);  // enters the upper half: must be checked
    EXPECT_GE(side_contact, 1);   // lies in a lateral facet: flagged (normal ⊥ pillar)
    // The wall's normal is perpendicular to the opposite pillar: only boundary contact spared it.
    EXPECT_EQ(sh::normal_dot_sign(wall, Vector3d::Zero(), Vector3d::UnitZ()), 0);
    EXPECT_EQ(sh::normal_dot_sign(in_side, Vector3d::Zero(), bis), 0);
  }
}

TEST(SectionContact, PinchedPrismSkipsFlatTets) {
  // Corner 2 singular (zero pillar): 4 non-degenerate tets; a face through the pinch point
  // outside the prism touches it there only.
  const std::array<Vector3d, 3> m{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
  const auto tets = split(m, {Vector3d::UnitZ(), Vector3d::UnitZ(), Vector3d::Zero()}, 0.2);
  EXPECT_EQ(tets.size(), 4u);
  const std::array<Vector3d, 3> outside{m[2], Vector3d(-1, 2, 1), Vector3d(-1, 2, -1)};
  const std::array<Vector3d, 3> own = m;
  int own_contact = 0;
  for (const auto& T : tets) {
    EXPECT_FALSE(sh::triangle_section_contact(outside, T));
    own_contact += sh::triangle_section_contact(own, T);
  }
  EXPECT_GE(own_contact, 2);
}

// The batched tet query (one tree traversal, a separating-plane rejection, then CGAL's exact
// triangle-tetrahedron test) against CGAL's test on every input face. Coordinates on a small
// integer grid make shared corners, touching edges and coplanar contacts common.
TEST(InputSurfaceIndex, TouchingTetsMatchBruteForceOnIntegerGrids) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(0, 5);
  auto point = [&] { return Vector3d(coord(rng), coord(rng), coord(rng)); };
  auto cgal = [](const Vector3d& p) { return K::Point_3(p.x(), p.y(), p.z()); };
  int touching = 0, total = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int nf = 40;
    Eigen::MatrixXd V(3 * nf, 3);
    Eigen::MatrixXi F(nf, 3);
    // Non-degenerate triangles only: CGAL 5.5's triangle-tetrahedron test reports contact for
    // some segment-shaped triangles that miss the tet (checked exactly by hand), so it is no
    // reference for them; input surfaces with such faces are rejected before a shell is built.
    for (int f = 0; f < nf; ++f) {
      Vector3d a, b, c;
      do {
        a = point();
        b = point();
        c = point();
      } while ((b - a).cross(c - a).squaredNorm() == 0);
      V.row(3 * f) = a.transpose();
      V.row(3 * f + 1) = b.transpose();
      V.row(3 * f + 2) = c.transpose();
      F.row(f) = Eigen::RowVector3i(3 * f, 3 * f + 1, 3 * f + 2);
    }
    const sh::InputSurfaceIndex index(V, F);
    std::vector<std::array<Vector3d, 4>> tets;
    while (tets.size() < 3) {
      std::array<Vector3d, 4> t{point(), point(), point(), point()};
      if ((t[1] - t[0]).cross(t[2] - t[0]).dot(t[3] - t[0]) != 0) tets.push_back(t);
    }
    std::vector<int> expected, single;
    for (int f = 0; f < nf; ++f) {
      const K::Triangle_3 tri(cgal(V.row(3 * f)), cgal(V.row(3 * f + 1)), cgal(V.row(3 * f + 2)));
      bool hit = false;
      for (const auto& t : tets) {
        const bool h = CGAL::do_intersect(
            tri, K::Tetrahedron_3(cgal(t[0]), cgal(t[1]), cgal(t[2]), cgal(t[3])));
        EXPECT_EQ(index.face_touches_tet(f, t), h) << "trial " << trial << " face " << f;
        hit |= h;
      }
      if (hit) expected.push_back(f);
    }
    EXPECT_EQ(index.faces_touching_tets(tets), expected) << "trial " << trial;
    for (const auto& t : tets)
      for (int f : index.faces_touching_tet(t)) single.push_back(f);
    std::sort(single.begin(), single.end());
    single.erase(std::unique(single.begin(), single.end()), single.end());
    EXPECT_EQ(single, expected) << "trial " << trial;
    touching += int(expected.size());
    total += nf;
  }
  // Both outcomes occur often enough for the comparison to mean something.
  EXPECT_GT(touching, total / 10);
  EXPECT_LT(touching, total * 9 / 10);
}

// Rays in the plane of input faces (CAD inputs: a pillar along a flat face's plane). CGAL 5.5's
// ray/triangle intersection returned the segment from the ray's source to a corner for a ray
// pointing away from a coplanar triangle, so ray_distance answered 0 and the shell refused a valid
// input ("cannot be made positive"). Reference: the ray clipped by the triangle's three edge
// half-planes (coplanar faces) or met at the plane x = 7 (the upright face).
TEST(InputSurfaceIndex, RayDistanceInTheFacesPlaneMatchesClipping) {
  Eigen::MatrixXd V(9, 3);
  V << 4, 0, 0, 6, 0, 0, 5, 2, 0,    // coplanar with every ray (z = 0)
      0, 4, 0, 2, 4, 0, 0, 6, 0,     //
      7, -1, -1, 7, 3, -1, 7, 1, 2;  // upright, crossing z = 0 on x = 7, y in [0, 2]
  Eigen::MatrixXi F(3, 3);
  F << 0, 1, 2, 3, 4, 5, 6, 7, 8;
  const sh::InputSurfaceIndex index(V, F);
  const double inf = std::numeric_limits<double>::infinity();
  // The ray clipped by the face's three edge half-planes (in-plane inward normals): the face in
  // the ray's plane; else the ray meets the face's plane at t and the point is tested the same way.
  auto reference = [&](int f, const Vector3d& o, const Vector3d& d) {
    const Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Vector3d n = (b - a).cross(c - a);
    double lo = 0, hi = inf;
    if (n.dot(d) != 0) {
      lo = hi = n.dot(a - o) / n.dot(d);
      if (lo < 0) return inf;
    } else if (n.dot(o - a) != 0) {
      return inf;
    }
    for (int k = 0; k < 3; ++k) {
      const Vector3d p = V.row(F(f, k)), q = V.row(F(f, (k + 1) % 3)), r = V.row(F(f, (k + 2) % 3));
      Vector3d nu = n.cross(q - p);
      if (nu.dot(r - p) < 0) nu = -nu;
      const double at0 = nu.dot(o - p), slope = nu.dot(d);
      if (lo == hi) {  // a point of the plane
        if (at0 + lo * slope < -1e-12 * nu.norm()) return inf;
      } else if (slope == 0) {
        if (at0 < 0) return inf;
      } else if (slope > 0) {
        lo = std::max(lo, -at0 / slope);
      } else {
        hi = std::min(hi, -at0 / slope);
      }
    }
    return lo <= hi ? lo : inf;
  };
  const std::vector<Vector3d> dirs = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0},  {0, -1, 0},
                                      {1, 1, 0}, {1, -2, 0}, {-1, 2, 0}, {-3, -1, 0}};
  int zero = 0, hits = 0, misses = 0, away_on_edge_line = 0;
  for (int x = -2; x <= 9; ++x)
    for (int y = -2; y <= 8; ++y)
      for (const Vector3d& dir : dirs) {
        // The direction unnormalized, so that the ray is exact (a rounded unit direction moves
        // its line off a corner it grazes).
        const Vector3d o(x, y, 0), d = dir.normalized();
        const double expected =
            std::min({reference(0, o, d), reference(1, o, d), reference(2, o, d)});
        const double got = index.ray_distance(o, dir, {});
        if (std::isinf(expected)) {
          EXPECT_TRUE(std::isinf(got)) << o.transpose() << " dir " << dir.transpose();
          ++misses;
        } else {
          EXPECT_NEAR(got, expected, 1e-12) << o.transpose() << " dir " << dir.transpose();
          ++(expected == 0 ? zero : hits);
        }
        // The failing configuration: the ray's line through a coplanar face's edge, pointing away.
        if (y == 0 && x > 6 && dir == Vector3d(1, 0, 0)) ++away_on_edge_line;
      }
  // Every outcome occurs: inside a face, a later hit, no hit, and the rays that used to get 0.
  EXPECT_GT(zero, 0);
  EXPECT_GT(hits, 50);
  EXPECT_GT(misses, 50);
  EXPECT_GT(away_on_edge_line, 0);
  // Ignored faces are skipped, coplanar or not.
  EXPECT_TRUE(std::isinf(index.ray_distance(Vector3d(5, 1, 0), Vector3d(1, 0, 0), {0, 2})));
  EXPECT_NEAR(index.ray_distance(Vector3d(3, 1, 0), Vector3d(1, 0, 0), {2}), 1.5, 1e-12);
}
