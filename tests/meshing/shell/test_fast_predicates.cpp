// The coarsening's fast paths against plain exact references: they must give the same answers,
// not close ones (the coarsened shell is compared byte for byte before and after them).
//   - locate_in_prism: a box rejection and the tet's own orientation reused for its facets;
//   - faces_touching_tets: semi-static plane filters before CGAL's exact orientation, and faces
//     the caller knows to touch reported without a test;
//   - triangle_intersects: box candidates, then the exact triangle test.
// Coordinates on small integer grids (exact zeros: shared corners, coplanar contacts) and the
// same configurations shrunk and shifted (rounded coordinates near every plane).

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <optional>
#include <random>
#include <vector>

#include "meshing/shell/prism_location.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace sh = curvefem::meshing::shell;
using Eigen::Vector3d;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;

namespace {

K::Point_3 cgal(const Vector3d& p) { return K::Point_3(p.x(), p.y(), p.z()); }

// locate_in_prism as first written: every split tet, four facet tests each with the corner's side
// computed again, no box rejection.
std::optional<sh::PrismCoordinates> reference_locate(const Eigen::Vector3i& F,
                                                     const std::array<Vector3d, 3>& base,
                                                     const std::array<Vector3d, 3>& mid,
                                                     const std::array<Vector3d, 3>& top,
                                                     const Vector3d& p) {
  constexpr double xy[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  const int r = curvefem::min_rotation(F);
  const K::Point_3 q = cgal(p);
  for (int half = 0; half < 2; ++half)
    for (const auto& tet : curvefem::split_tets(curvefem::is_type_a(F))) {
      Vector3d e[4];
      K::Point_3 c[4];
      for (int k = 0; k < 4; ++k) {
        const int local = (r + tet[k] % 3) % 3;
        e[k] = tet[k] < 3 ? (half == 0 ? base[local] : mid[local])
                          : (half == 0 ? mid[local] : top[local]);
        c[k] = cgal(e[k]);
      }
      if (CGAL::orientation(c[0], c[1], c[2], c[3]) == CGAL::COPLANAR) continue;
      static const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
      bool inside = true;
      for (int i = 0; i < 4 && inside; ++i) {
        const auto& fc = faces[i];
        const auto side = CGAL::orientation(c[fc[0]], c[fc[1]], c[fc[2]], q);
        inside =
            side == CGAL::COPLANAR || side == CGAL::orientation(c[fc[0]], c[fc[1]], c[fc[2]], c[i]);
      }
      if (!inside) continue;
      Eigen::Matrix3d A;
      A << e[1] - e[0], e[2] - e[0], e[3] - e[0];
      const Vector3d l = A.colPivHouseholderQr().solve(p - e[0]);
      const double w[4] = {1 - l.sum(), l[0], l[1], l[2]};
      sh::PrismCoordinates out;
      for (int k = 0; k < 4; ++k) {
        out.u += w[k] * xy[tet[k] % 3][0];
        out.v += w[k] * xy[tet[k] % 3][1];
        out.h += w[k] * ((tet[k] < 3 ? -1.0 : 0.0) + half);
      }
      return out;
    }
  return std::nullopt;
}

// A point map for "the same configuration, rounded": x -> offset + scale * x, which is inexact
// for most coordinates, so orientations that were exactly zero become tiny of either sign.
struct Placement {
  double scale = 1;
  Vector3d offset = Vector3d::Zero();
  Vector3d operator()(const Vector3d& x) const { return offset + scale * x; }
};

const std::array<Placement, 3> k_placements{Placement{1, Vector3d::Zero()},
                                            Placement{0.1, Vector3d(0.3, 0.7, 0.1)},
                                            Placement{1e-3, Vector3d(123.456, -7.89, 0.001)}};

}  // namespace

TEST(FastPredicates, LocateInPrismMatchesTheReference) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> coord(-2, 6), id(0, 50);
  int inside = 0, outside = 0;
  for (const Placement& place : k_placements)
    for (int trial = 0; trial < 400; ++trial) {
      auto point = [&] { return place(Vector3d(coord(rng), coord(rng), coord(rng))); };
      Eigen::Vector3i F(id(rng), id(rng), id(rng));
      if (F[0] == F[1] || F[1] == F[2] || F[0] == F[2]) continue;
      // A roughly upright prism on a random middle triangle (not necessarily positive: the
      // function is defined for any corners).
      std::array<Vector3d, 3> b, m, t;
      for (int k = 0; k < 3; ++k) {
        m[k] = point();
        const Vector3d up =
            place.scale * Vector3d(coord(rng) % 2, coord(rng) % 2, 2 + coord(rng) % 3);
        t[k] = m[k] + up;
        b[k] = m[k] - up;
      }
      std::vector<Vector3d> queries;
      for (int q = 0; q < 30; ++q) queries.push_back(point());
      for (const auto* layer : {&b, &m, &t})
        for (const Vector3d& c : *layer) queries.push_back(c);  // corners: on the boundary
      queries.push_back((m[0] + m[1]) / 2);
      queries.push_back((b[0] + t[1] + m[2]) / 3);
      // One locator for all the queries (what the coarsening's re-homing uses) and the
      // one-point function give the reference's answers.
      const sh::PrismLocator locator(F, b, m, t);
      for (const Vector3d& q : queries) {
        const auto got = sh::locate_in_prism(F, b, m, t, q);
        const auto want = reference_locate(F, b, m, t, q);
        const auto reused = locator.locate(q);
        ASSERT_EQ(got.has_value(), want.has_value()) << "trial " << trial;
        ASSERT_EQ(reused.has_value(), want.has_value()) << "trial " << trial;
        if (reused) {
          EXPECT_EQ(reused->u, want->u);
          EXPECT_EQ(reused->v, want->v);
          EXPECT_EQ(reused->h, want->h);
        }
        if (!got) {
          ++outside;
          continue;
        }
        ++inside;
        EXPECT_EQ(got->u, want->u);
        EXPECT_EQ(got->v, want->v);
        EXPECT_EQ(got->h, want->h);
      }
    }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 1000);
}

// faces_touching_tets (with and without faces given as known) and triangle_intersects against
// CGAL's exact tests on every face.
TEST(FastPredicates, TouchingTetsAndTriangleQueriesMatchCgal) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> coord(0, 5);
  int touching = 0, total = 0, meeting = 0, triangles = 0;
  for (const Placement& place : k_placements)
    for (int trial = 0; trial < 40; ++trial) {
      auto point = [&] { return place(Vector3d(coord(rng), coord(rng), coord(rng))); };
      const int nf = 40;
      Eigen::MatrixXd V(3 * nf, 3);
      Eigen::MatrixXi F(nf, 3);
      for (int f = 0; f < nf; ++f) {
        Vector3d a, b, c;
        do {
          a = point();
          b = point();
          c = point();
        } while (CGAL::collinear(cgal(a), cgal(b), cgal(c)));
        V.row(3 * f) = a.transpose();
        V.row(3 * f + 1) = b.transpose();
        V.row(3 * f + 2) = c.transpose();
        F.row(f) = Eigen::RowVector3i(3 * f, 3 * f + 1, 3 * f + 2);
      }
      const sh::InputSurfaceIndex index(V, F);
      std::vector<std::array<Vector3d, 4>> tets;
      while (tets.size() < 3) {
        std::array<Vector3d, 4> t{point(), point(), point(), point()};
        if (!CGAL::coplanar(cgal(t[0]), cgal(t[1]), cgal(t[2]), cgal(t[3]))) tets.push_back(t);
      }
      std::vector<int> expected;
      for (int f = 0; f < nf; ++f) {
        const K::Triangle_3 tri(cgal(V.row(3 * f)), cgal(V.row(3 * f + 1)), cgal(V.row(3 * f + 2)));
        bool hit = false;
        for (const auto& t : tets)
          hit = hit || CGAL::do_intersect(
                           tri, K::Tetrahedron_3(cgal(t[0]), cgal(t[1]), cgal(t[2]), cgal(t[3])));
        if (hit) expected.push_back(f);
      }
      EXPECT_EQ(index.faces_touching_tets(tets), expected) << "trial " << trial;
      // Every other touching face given as known: the same list.
      std::vector<int> known;
      for (std::size_t i = 0; i < expected.size(); i += 2) known.push_back(expected[i]);
      EXPECT_EQ(index.faces_touching_tets(tets, known), expected) << "trial " << trial;
      touching += int(expected.size());
      total += nf;

      // triangle_intersects: no singular corners, so it is "meets any input face".
      for (int q = 0; q < 10; ++q) {
        // Small triangles (edges of one grid step), so that both answers are common.
        std::uniform_int_distribution<int> step(0, 1);
        const Vector3d a = point();
        auto near = [&] {
          return Vector3d(a + place.scale * Vector3d(step(rng), step(rng), step(rng)));
        };
        std::array<Vector3d, 3> c{a, near(), near()};
        if (CGAL::collinear(cgal(c[0]), cgal(c[1]), cgal(c[2]))) continue;
        const K::Triangle_3 query(cgal(c[0]), cgal(c[1]), cgal(c[2]));
        bool want = false;
        for (int f = 0; f < nf && !want; ++f)
          want = CGAL::do_intersect(query, K::Triangle_3(cgal(V.row(3 * f)), cgal(V.row(3 * f + 1)),
                                                         cgal(V.row(3 * f + 2))));
        EXPECT_EQ(index.triangle_intersects(c, {false, false, false}, Eigen::Vector3i(-1, -1, -1)),
                  want)
            << "trial " << trial;
        meeting += want;
        ++triangles;
      }
    }
  EXPECT_GT(touching, total / 10);
  EXPECT_LT(touching, total * 9 / 10);
  EXPECT_GT(meeting, triangles / 10);
  EXPECT_LT(meeting, triangles * 9 / 10);
}

// Triangles whose corners are rounded affine combinations of a tet facet's corners: they lie on
// the facet's plane up to rounding, so the floating-point orientation is as small as its own
// error and often of the wrong sign. The filter must hand every such case to the exact predicate.
TEST(FastPredicates, TrianglesRoundedOntoATetFacetMatchCgal) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0, 1), weight(-0.3, 1.3);
  int touching = 0, total = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::array<Vector3d, 4> t;
    for (auto& p : t) p = Vector3d(unit(rng), unit(rng), unit(rng));
    if (CGAL::coplanar(cgal(t[0]), cgal(t[1]), cgal(t[2]), cgal(t[3]))) continue;
    const int nf = 20;
    Eigen::MatrixXd V(3 * nf, 3);
    Eigen::MatrixXi F(nf, 3);
    for (int f = 0; f < nf; ++f) {
      const int j = f % 4;  // the facet opposite corner j
      const Vector3d &a = t[(j + 1) % 4], &b = t[(j + 2) % 4], &c = t[(j + 3) % 4];
      std::array<Vector3d, 3> corner;
      do {
        for (auto& q : corner) {
          const double u = weight(rng), v = weight(rng);
          q = a + u * (b - a) + v * (c - a);  // rounded: on the plane up to an ulp or so
        }
      } while (CGAL::collinear(cgal(corner[0]), cgal(corner[1]), cgal(corner[2])));
      for (int k = 0; k < 3; ++k) V.row(3 * f + k) = corner[std::size_t(k)].transpose();
      F.row(f) = Eigen::RowVector3i(3 * f, 3 * f + 1, 3 * f + 2);
    }
    const sh::InputSurfaceIndex index(V, F);
    const K::Tetrahedron_3 T(cgal(t[0]), cgal(t[1]), cgal(t[2]), cgal(t[3]));
    std::vector<int> expected;
    for (int f = 0; f < nf; ++f)
      if (CGAL::do_intersect(
              K::Triangle_3(cgal(V.row(3 * f)), cgal(V.row(3 * f + 1)), cgal(V.row(3 * f + 2))), T))
        expected.push_back(f);
    EXPECT_EQ(index.faces_touching_tets({t}), expected) << "trial " << trial;
    touching += int(expected.size());
    total += nf;
  }
  EXPECT_GT(touching, total / 10);
  EXPECT_LT(touching, total * 9 / 10);
}
