// Nested cages (thesis §4.5, Fig. 4.29): each cage is the top surface of a shell around the one
// inside it. Checked here with code independent of the construction: exact self-intersection
// and layer-against-layer tests (meshing/check), nesting by winding number, and the composed
// maps cage → input → cage returning every sampled point.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "meshing/check/self_intersections.hpp"
#include "meshing/check/surface_distance.hpp"
#include "meshing/core/adversarial.hpp"
#include "meshing/core/error.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/shell/nested_cages.hpp"
#include "tests/support/test_support.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {

// roundtrip: the largest |up(down(x)) - x| allowed, relative to the longest bbox edge.
void expect_nested_and_mapped(const sh::NestedCages& cages, double roundtrip = 1e-12) {
  const double unit = curvefem::bbox_longest_edge(cages.input.V);
  std::vector<const SurfaceMesh*> layers{&cages.input};
  for (const auto& l : cages.layers) layers.push_back(&l.cage);
  for (std::size_t a = 0; a < layers.size(); ++a) {
    EXPECT_EQ(curvefem::check::count_self_intersecting_pairs(layers[a]->V, layers[a]->F), 0)
        << "layer " << a;
    for (std::size_t b = a + 1; b < layers.size(); ++b) {
      EXPECT_EQ(curvefem::check::intersecting_pairs_between(layers[a]->V, layers[a]->F,
                                                            layers[b]->V, layers[b]->F),
                0)
          << a << " " << b;
      // Every vertex of the inner layer is inside the outer one.
      for (int v = 0; v < layers[a]->num_vertices(); v += 7)
        EXPECT_NEAR(curvefem::check::winding_number(layers[b]->V, layers[b]->F,
                                                    layers[a]->V.row(v).transpose()),
                    1.0, 1e-6)
            << a << " " << b;
    }
  }
  for (int k = 0; k < int(cages.layers.size()); ++k) {
    const SurfaceMesh& cage = cages.layers[std::size_t(k)].cage;
    EXPECT_TRUE(cages.layers[std::size_t(k)].verification.valid()) << k;
    std::vector<sh::MeshPoint> points;
    Eigen::MatrixXd start(3 * cage.num_faces(), 3);
    for (int f = 0; f < cage.num_faces(); ++f) {
      const Eigen::Vector3d b[3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {1, 0, 0}, {0.6, 0.3, 0.1}};
      for (const auto& bary : b) {
        Eigen::Vector3d x = Eigen::Vector3d::Zero();
        for (int c = 0; c < 3; ++c) x += bary[c] * Eigen::Vector3d(cage.V.row(cage.F(f, c)));
        start.row(Eigen::Index(points.size())) = x.transpose();
        points.push_back({f, bary});
      }
    }
    int down_failures = -1, up_failures = -1;
    std::vector<char> on_fill;
    const Eigen::MatrixXd down = sh::cage_to_input(cages, k, points, &down_failures, &on_fill);
    ASSERT_EQ(down_failures, 0) << k;
    EXPECT_LT(curvefem::check::distances_to_surface(down, cages.input.V, cages.input.F).maxCoeff(),
              1e-13 * unit)
        << k;
    // One to one except where the way down meets a fill (those points go to the filled point).
    std::vector<Eigen::Index> mapped;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (!on_fill[i]) mapped.push_back(Eigen::Index(i));
    ASSERT_FALSE(mapped.empty()) << k;
    const Eigen::MatrixXd up = sh::input_to_cage(cages, k, down(mapped, Eigen::all), &up_failures);
    ASSERT_EQ(up_failures, 0) << k;
    EXPECT_LT((up - start(mapped, Eigen::all)).rowwise().norm().maxCoeff(), roundtrip * unit) << k;
  }
}

// Pairs of faces, one of each surface, that intersect or touch.
int pairs_between(const SurfaceMesh& a, const SurfaceMesh& b) {
  return curvefem::check::intersecting_pairs_between(a.V, a.F, b.V, b.F);
}

}  // namespace

TEST(NestedCages, ThreeCoarseningCagesAroundANoisySphereAreNestedAndMapped) {
  const SurfaceMesh input = curvefem::make_adversarial("noise_sphere_5");  // 1280 faces
  sh::NestedCageOptions o;
  o.layers = 3;
  o.threads = 1;
  const sh::NestedCages cages = sh::build_nested_cages(input, o);
  ASSERT_EQ(cages.layers.size(), 3u);
  // Coarser layer by layer (measured 474, 386, 370 faces).
  EXPECT_LT(cages.layers[0].cage.num_faces(), input.num_faces() / 2);
  for (int k = 1; k < 3; ++k)
    EXPECT_LE(cages.layers[std::size_t(k)].cage.num_faces(),
              cages.layers[std::size_t(k - 1)].cage.num_faces());
  expect_nested_and_mapped(cages);
}

TEST(NestedCages, ATopSurfaceThatMeetsItselfAcrossAGapIsShrunkApart) {
  // A split ring whose gap is 0.1 ε: the simplified shells' top surfaces meet across the gap
  // (19 self-intersecting pairs measured on layer 1), and shrinking their pillars frees them.
  const SurfaceMesh input = curvefem::make_adversarial("split_ring_01");
  sh::NestedCageOptions o;
  o.layers = 2;
  o.threads = 1;
  const sh::NestedCages cages = sh::build_nested_cages(input, o);
  ASSERT_EQ(cages.layers.size(), 2u);
  EXPECT_GT(cages.layers[0].self_intersecting_pairs_before, 0);
  EXPECT_GT(cages.layers[0].shrink_rounds, 0);
  EXPECT_GT(cages.layers[0].shrunk_pillars, 0);
  expect_nested_and_mapped(cages);
}

TEST(NestedCages, PinchPointsOfACadCageAreShortenedAwaySoTheNextCageDoesNotTouchIt) {
  // The dev hinge (a CAD part, 1,212 faces): its simplified first and second cages have top
  // vertices that no direction sees (pinch points), so the next layer's shell is pinched there
  // and the next cage touches the one inside it. Measured with one thread: 2 and 6 pinch points,
  // all shortened away.
  const auto dir = curvefem::test::shared_data_dir();
  if (!dir) GTEST_SKIP() << "../shared/data not found: nested cages of the dev hinge skipped";
  const SurfaceMesh input = curvefem::io::read_surface(*dir / "dev" / "hinge.obj");
  sh::NestedCageOptions o;
  o.layers = 3;
  o.threads = 1;
  {
    o.unpinch = false;  // what it fixes: a later layer pinched, its cage touching the layer inside
    const sh::NestedCages touching = sh::build_nested_cages(input, o);
    int pinched = 0;
    for (const auto& l : touching.layers) pinched += l.singular_vertices;
    EXPECT_GT(pinched, 0);
    int pairs = 0;
    for (std::size_t k = 1; k < touching.layers.size(); ++k)
      pairs += curvefem::check::intersecting_pairs_between(
          touching.layers[k - 1].cage.V, touching.layers[k - 1].cage.F, touching.layers[k].cage.V,
          touching.layers[k].cage.F);
    EXPECT_GT(pairs, 0);
  }
  o.unpinch = true;
  const sh::NestedCages cages = sh::build_nested_cages(input, o);
  ASSERT_EQ(cages.layers.size(), 3u);
  int before = 0;
  for (int k = 0; k < 3; ++k) {
    const sh::CageLayer& l = cages.layers[std::size_t(k)];
    EXPECT_EQ(l.singular_vertices, 0) << k;  // input and cages: no pinched shell
    if (k < 2) {
      EXPECT_EQ(l.top_pinch_points, 0) << k;
    }
    before += l.top_pinch_points_before;
  }
  EXPECT_GT(before, 0);
  // The shortened shells are thin where the pinch points were (the third cage's smallest gap to
  // the second is about 4e-8 of the bbox), and the map's roundtrip loses digits across them:
  // measured 4e-10, held to `curvefem shell --cages`' own bound of 1e-9.
  expect_nested_and_mapped(cages, 1e-9);
}

TEST(NestedCages, SingularVerticesOfTheInputAreFilledSoTheFirstCageDoesNotTouchIt) {
  // A sphere with 8 thin needles: no direction sees all faces at a needle's tip, so the first
  // shell has zero thickness there (8 singular vertices) and its top surface touches the input.
  // The cage is the top surface's union with a small tetrahedron around each tip (thesis §4.5,
  // pinching alternative).
  const SurfaceMesh input = curvefem::make_adversarial("needle_sphere_8");
  sh::NestedCageOptions o;
  o.layers = 2;
  o.threads = 1;
  {
    o.fill = false;  // what it fixes
    const sh::NestedCages touching = sh::build_nested_cages(input, o);
    EXPECT_EQ(touching.layers[0].singular_vertices, 8);
    EXPECT_EQ(touching.layers[0].unfilled_points, 8);
    EXPECT_GT(pairs_between(input, touching.layers[0].cage), 0);
  }
  o.fill = true;
  const sh::NestedCages cages = sh::build_nested_cages(input, o);
  ASSERT_EQ(cages.layers.size(), 2u);
  const sh::CageLayer& first = cages.layers[0];
  EXPECT_EQ(first.singular_vertices, 8);
  EXPECT_EQ(first.filled_points, 8);
  EXPECT_EQ(first.unfilled_points, 0);
  EXPECT_GT(first.fill_size, 0);
  ASSERT_EQ(first.cage_face_parent.size(), std::size_t(first.cage.num_faces()));
  // Each tip is strictly inside the first cage: off it, and wound once.
  const sh::Shell& shell = first.shell;
  Eigen::MatrixXd tips(8, 3);
  int n = 0;
  for (int v = 0; v < int(shell.top.rows()); ++v)
    if (shell.top.row(v) == shell.mid.row(v)) {
      ASSERT_LT(n, 8);
      tips.row(n++) = shell.mid.row(v);
    }
  ASSERT_EQ(n, 8);
  const Eigen::VectorXd off =
      curvefem::check::distances_to_surface(tips, first.cage.V, first.cage.F);
  EXPECT_GT(off.minCoeff(), 0);
  for (int i = 0; i < 8; ++i)
    EXPECT_NEAR(
        curvefem::check::winding_number(first.cage.V, first.cage.F, tips.row(i).transpose()), 1.0,
        1e-6);
  // The fill's faces map to the tips themselves, the rest one to one (expect_nested_and_mapped).
  std::vector<sh::MeshPoint> on;
  for (int f = 0; f < first.cage.num_faces(); ++f)
    if (first.cage_face_on_fill[std::size_t(f)]) on.push_back({f, Eigen::Vector3d(0.2, 0.3, 0.5)});
  ASSERT_GT(on.size(), 0u);
  std::vector<char> on_fill;
  const Eigen::MatrixXd down = sh::cage_to_input(cages, 0, on, nullptr, &on_fill);
  for (Eigen::Index i = 0; i < down.rows(); ++i) {
    EXPECT_TRUE(on_fill[std::size_t(i)]);
    double nearest = HUGE_VAL;
    for (int t = 0; t < 8; ++t) nearest = std::min(nearest, (down.row(i) - tips.row(t)).norm());
    EXPECT_EQ(nearest, 0) << i;
  }
  expect_nested_and_mapped(cages);
}

TEST(NestedCages, BadOptionsAreRefused) {
  const SurfaceMesh input = curvefem::make_adversarial("sphere_coarse");
  sh::NestedCageOptions o;
  o.layers = 0;
  EXPECT_THROW(sh::build_nested_cages(input, o), curvefem::InputError);
  o.layers = 1;
  o.shrink = 1.0;
  EXPECT_THROW(sh::build_nested_cages(input, o), curvefem::InputError);
}
