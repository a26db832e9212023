// SCAF bijective parameterization (meshing/param) on generated inputs: every iteration is
// checked by the independent exact verifier (uv_check), the energy must be monotone, ≥ 4, and
// within 1% of a converged reference run.
#include <gtest/gtest.h>

#include <cmath>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/param/cut_mesh.hpp"
#include "meshing/param/scaf.hpp"
#include "meshing/param/symmetric_dirichlet.hpp"
#include "meshing/param/tutte.hpp"
#include "meshing/param/uv_check.hpp"
#include "tests/meshing/param/param_inputs.hpp"

using namespace curvefem;
using namespace curvefem::meshing::param;

namespace {

struct CheckedRun {
  ScafResult result;
  int checked = 0;
  long long worst_flips = 0, worst_overlaps = 0, worst_nested = 0, worst_scaffold_flips = 0;
};

// Optimises and checks the charts (and the charts + scaffold together) after every iteration.
CheckedRun run_checked(const CutMesh& cut, int iterations, double tolerance = 0) {
  CheckedRun run;
  ScafOptions options;
  options.max_iterations = iterations;
  options.tolerance = tolerance;
  options.on_iteration = [&](const IterationStats&, const Eigen::MatrixXd& uv, const Scaffold& s) {
    const UvCheck c = check_uv_map(uv, cut.F);
    run.worst_flips = std::max(run.worst_flips, c.flips);
    run.worst_overlaps = std::max(run.worst_overlaps, c.overlaps);
    run.worst_nested = std::max(run.worst_nested, c.nested_charts);
    // charts + scaffold tile the box: no flip there either
    Eigen::MatrixXd all(uv.rows() + s.V.rows(), 2);
    all << uv, s.V;
    Eigen::MatrixXi F(cut.F.rows() + s.F.rows(), 3);
    F << cut.F, s.F;
    run.worst_scaffold_flips = std::max(run.worst_scaffold_flips, check_uv_map(all, F).flips);
    ++run.checked;
  };
  run.result = scaf_optimize(cut, tutte_layout(cut), options);
  return run;
}

double reference_energy(const CutMesh& cut, int iterations) {
  ScafOptions options;
  options.max_iterations = iterations;
  options.tolerance = 1e-10;
  return scaf_optimize(cut, tutte_layout(cut), options).history.back().energy;
}

void expect_valid(const CutMesh& cut, const CheckedRun& run, double reference) {
  const auto& h = run.result.history;
  ASSERT_GE(h.size(), 2u);
  EXPECT_EQ(run.checked, int(h.size()));
  EXPECT_EQ(run.worst_flips, 0);
  EXPECT_EQ(run.worst_overlaps, 0);
  EXPECT_EQ(run.worst_nested, 0);
  EXPECT_EQ(run.worst_scaffold_flips, 0);
  for (std::size_t i = 1; i < h.size(); ++i) {
    EXPECT_LE(h[i].energy, h[i - 1].energy) << "iteration " << i;
    EXPECT_GT(h[i].min_singular, 0) << "iteration " << i;
  }
  const double e = h.back().energy;
  EXPECT_GE(e, 4.0 - 1e-12);
  EXPECT_LE(e, 1.01 * reference) << "energy " << e << " vs reference " << reference;
  EXPECT_LT(e, h.front().energy);  // it did optimise
  const UvCheck c = check_uv_map(run.result.uv, cut.F);
  EXPECT_TRUE(c.bijective());
  EXPECT_LT(c.area_rel_error, 1e-9);
  EXPECT_EQ(c.components, cut.num_charts);
}

}  // namespace

TEST(ParamEnergy, SymmetricDirichletValues) {
  const double a = 0.3;
  Eigen::Matrix2d R;
  R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  EXPECT_NEAR(symmetric_dirichlet(R), 4.0, 1e-14);
  EXPECT_NEAR(symmetric_dirichlet(2.0 * R), 2 * (4 + 0.25), 1e-13);
  Eigen::Matrix2d flip;
  flip << 1, 0, 0, -1;
  EXPECT_TRUE(std::isinf(symmetric_dirichlet(flip)));
  Eigen::Matrix2d J;
  J << 1.3, 0.4, -0.2, 0.7;
  const Eigen::Vector2d s = singular_values(J);
  EXPECT_NEAR(s[0] * s[1], J.determinant(), 1e-14);
  EXPECT_NEAR(s.squaredNorm(), J.squaredNorm(), 1e-14);
  // SLIM weights: the proxy's gradient 2 Wᵀ W (J − R) equals ∂D/∂J.
  Eigen::Matrix2d W, Rot;
  slim_weights(J, W, Rot);
  EXPECT_NEAR((2 * W.transpose() * W * (J - Rot) - symmetric_dirichlet_gradient(J)).norm(), 0,
              1e-12);
  // the gradient against a central difference
  Eigen::Matrix2d dJ;
  dJ << 0.1, -0.3, 0.2, 0.05;
  const double h = 1e-6;
  const double fd = (symmetric_dirichlet(J + h * dJ) - symmetric_dirichlet(J - h * dJ)) / (2 * h);
  EXPECT_NEAR(symmetric_dirichlet_gradient(J).cwiseProduct(dJ).sum(), fd, 1e-7);
}

TEST(ParamCut, TorusNeedsSeamsAndBadSeamsAreRejected) {
  auto [torus, seams] = test::cut_torus(2, 0.7, 24, 12);
  try {
    cut_into_charts(torus, {});
    FAIL() << "an uncut torus is not a disk";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("chart 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Euler characteristic 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0 boundary loop"), std::string::npos) << e.what();
  }
  // one seam loop only: an annulus (χ = 0, 2 boundary loops)
  std::vector<std::array<int, 2>> meridian(seams.begin(), seams.begin() + 12);
  try {
    cut_into_charts(torus, meridian);
    FAIL() << "a torus cut along one loop is an annulus";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 boundary loop"), std::string::npos) << e.what();
  }
  EXPECT_THROW(cut_into_charts(torus, {{0, 100}}), InputError);  // not an edge
  const CutMesh cut = cut_into_charts(torus, seams);
  EXPECT_EQ(cut.num_charts, 1);
  // the seam vertices are split: 24 × 12 vertices, + 24 + 12 copies along the loops, + 1 corner
  EXPECT_EQ(cut.num_uv_vertices(), 24 * 12 + 24 + 12 + 1);
  EXPECT_EQ(cut.boundary_loops[0].size(), std::size_t(2 * (24 + 12)));
}

TEST(ParamCut, GroupsAreCharts) {
  SurfaceMesh grid = test::bump_disk(6, 24, 0.2, 0.5);
  grid.tags.resize(grid.num_faces());
  for (int f = 0; f < grid.num_faces(); ++f) {
    const Eigen::Vector3d c =
        (grid.V.row(grid.F(f, 0)) + grid.V.row(grid.F(f, 1)) + grid.V.row(grid.F(f, 2))) / 3;
    grid.tags[f] = c.x() > 0 ? 1 : 2;
  }
  grid.tag_names = {{1, "east"}, {2, "west"}};
  const CutMesh cut = cut_into_charts(grid, {});
  EXPECT_EQ(cut.num_charts, 2);
  EXPECT_NE(cut.chart_names[0].find("east"), std::string::npos);
  CutOptions whole;
  whole.split_groups = false;
  EXPECT_EQ(cut_into_charts(grid, {}, whole).num_charts, 1);
}

TEST(ParamTutte, EmbeddingHasNoFlipAndMatchesArea) {
  const SurfaceMesh disk = test::bump_disk(10, 40, 1.5, 0.3);
  const CutMesh cut = cut_into_charts(disk, {});
  for (TutteWeights w : {TutteWeights::uniform, TutteWeights::mean_value}) {
    const Eigen::MatrixXd uv = tutte_layout(cut, w);
    const UvCheck c = check_uv_map(uv, cut.F);
    EXPECT_TRUE(c.bijective());
    const RestShapes rest = rest_shapes(cut);
    EXPECT_NEAR(c.triangle_area, rest.area.sum(), 1e-9 * rest.area.sum());
  }
}

// The verifier must see what it claims to see: a flipped triangle, crossing boundaries, a chart
// inside another, and two charts touching at a point.
TEST(ParamCheck, DetectsFlipsOverlapsAndNesting) {
  Eigen::MatrixXd uv(6, 2);
  uv << 0, 0, 4, 0, 0, 4, 1, 1, 2, 1, 1, 2;
  Eigen::MatrixXi F(2, 3);
  F << 0, 1, 2, 3, 4, 5;
  UvCheck c = check_uv_map(uv, F);  // small triangle inside the big one
  EXPECT_EQ(c.flips, 0);
  EXPECT_EQ(c.overlaps, 0);
  EXPECT_EQ(c.nested_charts, 1);
  EXPECT_FALSE(c.bijective());
  uv.row(4) << 5, 1;  // now its edges cross the big triangle's hypotenuse
  c = check_uv_map(uv, F);
  EXPECT_GE(c.overlaps, 2);
  uv.bottomRows(3) << 4, 0, 8, 0, 4, 4;  // touching at the point (4, 0) only: 2 × 2 edge pairs
  c = check_uv_map(uv, F);
  EXPECT_EQ(c.overlaps, 4);
  uv.bottomRows(3) << 5, 0, 8, 0, 5, 4;  // separate
  c = check_uv_map(uv, F);
  EXPECT_TRUE(c.bijective());
  F.row(1) << 3, 5, 4;  // clockwise
  c = check_uv_map(uv, F);
  EXPECT_EQ(c.flips, 1);
  // a fold: a disk of two triangles whose second one is folded back into the first; its boundary
  // (0, 0) (2, 0) (1, 0.5) (0, 2) is still a simple polygon: only the flip test sees it
  Eigen::MatrixXd fold(4, 2);
  fold << 0, 0, 2, 0, 0, 2, 1, 0.5;
  Eigen::MatrixXi G(2, 3);
  G << 0, 1, 2, 1, 3, 2;
  c = check_uv_map(fold, G);
  EXPECT_EQ(c.flips, 1);
  EXPECT_EQ(c.overlaps, 0);
  EXPECT_FALSE(c.bijective());
}

TEST(ParamScaf, HighCurvatureDisk) {
  const SurfaceMesh disk = test::bump_disk(14, 56, 1.6, 0.28);
  const CutMesh cut = cut_into_charts(disk, {});
  const CheckedRun run = run_checked(cut, 30);
  expect_valid(cut, run, reference_energy(cut, 200));
  EXPECT_GT(run.result.history.front().energy - 0.3, run.result.history.back().energy);
}

TEST(ParamScaf, CutTorus) {
  auto [torus, seams] = test::cut_torus(2, 0.8, 40, 16);
  const CutMesh cut = cut_into_charts(torus, seams);
  const CheckedRun run = run_checked(cut, 30);
  expect_valid(cut, run, reference_energy(cut, 200));
}

TEST(ParamScaf, SeveralChartsArePackedWithoutOverlap) {
  std::vector<SurfaceMesh> parts;
  for (int i = 0; i < 4; ++i)
    parts.push_back(test::bump_disk(8, 32, 0.6 + 0.4 * i, 0.3, Eigen::Vector3d(3.0 * i, 0, 0)));
  parts.push_back(test::spiral_strip(1.0, 40, 2, 0.4, 1.0));
  const SurfaceMesh mesh = test::concatenate(parts);
  const CutMesh cut = cut_into_charts(mesh, {});
  ASSERT_EQ(cut.num_charts, 5);
  const CheckedRun run = run_checked(cut, 30);
  expect_valid(cut, run, reference_energy(cut, 200));
}

TEST(ParamScaf, LongSpiralStrip) {
  const SurfaceMesh strip = test::spiral_strip(3.0, 150, 2, 0.5, 1.0);
  const CutMesh cut = cut_into_charts(strip, {});
  const CheckedRun run = run_checked(cut, 60);
  // The strip is flat: the strip itself is a bijective isometry, so the minimum is exactly 4.
  expect_valid(cut, run, 4.0);
}

// A closed sphere cut along one edge path (a "dev mesh cut to a disk" in miniature): the whole
// sphere is squeezed into the disk by Tutte's map (E 6.48 here, 4.59 after 40 iterations).
TEST(ParamScaf, SphereCutAlongAPath) {
  const SurfaceMesh sphere = make_icosphere(3);
  // BFS over edges from vertex 0 to the last vertex reached: a simple path of edges.
  std::vector<std::vector<int>> adj(sphere.num_vertices());
  for (int f = 0; f < sphere.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) adj[sphere.F(f, k)].push_back(sphere.F(f, (k + 1) % 3));
  std::vector<int> prev(sphere.num_vertices(), -2), order{0};
  prev[0] = -1;
  for (std::size_t i = 0; i < order.size(); ++i)
    for (int w : adj[order[i]])
      if (prev[w] == -2) {
        prev[w] = order[i];
        order.push_back(w);
      }
  std::vector<std::array<int, 2>> seams;
  for (int v = order.back(); prev[v] >= 0; v = prev[v]) seams.push_back({prev[v], v});
  ASSERT_GE(seams.size(), 4u);
  const CutMesh cut = cut_into_charts(sphere, seams);
  ASSERT_EQ(cut.num_charts, 1);
  const CheckedRun run = run_checked(cut, 40);
  const auto& h = run.result.history;
  EXPECT_EQ(run.worst_flips, 0);
  EXPECT_EQ(run.worst_overlaps, 0);
  EXPECT_EQ(run.worst_scaffold_flips, 0);
  for (std::size_t i = 1; i < h.size(); ++i) EXPECT_LE(h[i].energy, h[i - 1].energy);
  EXPECT_LT(h.back().energy, 0.75 * h.front().energy);
  EXPECT_GT(h.back().min_singular, 0);
  EXPECT_TRUE(check_uv_map(run.result.uv, cut.F).bijective());
}
