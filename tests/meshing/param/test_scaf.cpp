// SCAF bijective parameterization (meshing/param) on generated inputs: every iteration is
// checked by the independent exact verifier (uv_check), the energy must be monotone, ≥ 4, and
// within 1% of a converged reference run. ~1–2 s each: label integration.
#include <gtest/gtest.h>

#include <cmath>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/param/cut_mesh.hpp"
#include "meshing/param/scaf.hpp"
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
// newton < 0: the default Newton phase.
CheckedRun run_checked(const CutMesh& cut, int iterations, double tolerance = 0, int newton = -1) {
  CheckedRun run;
  ScafOptions options;
  options.max_iterations = iterations;
  options.tolerance = tolerance;
  if (newton >= 0) options.newton_iterations = newton;
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

// SLIM to `iterations` at tolerance 1e-10, then 50 Newton iterations: the SLIM reference alone
// was 0.4% above the minimum on the spiral strip (benchmarks/results/param.md).
double reference_energy(const CutMesh& cut, int iterations) {
  ScafOptions options;
  options.max_iterations = iterations;
  options.tolerance = 1e-10;
  options.newton_iterations = 50;
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

// The Newton phase (thesis §3.3, after Rabinovich et al.): from SLIM stopped at a relative
// decrease of 1e-6, projected Newton goes on to numerical convergence. Checked like every SCAF
// run after each iteration (no flip, no overlap, charts + scaffold a tiling, E_M monotone); it
// must end below the SLIM result of the same tolerance and at the converged reference (200 SLIM
// iterations at 1e-10, then 50 Newton ones) to 1e-9, take full steps at the end, and shrink the
// gradient of E.
TEST(ParamScaf, NewtonPhaseConvergesFromTheSlimResult) {
  auto [torus, seams] = test::cut_torus(2, 0.8, 40, 16);
  const CutMesh cut = cut_into_charts(torus, seams);
  const CheckedRun slim = run_checked(cut, 100, 1e-6, 0);
  const CheckedRun newton = run_checked(cut, 100, 1e-6, 40);
  const double reference = reference_energy(cut, 200);
  expect_valid(cut, newton, reference);
  const auto& h = newton.result.history;
  ASSERT_GT(newton.result.newton_iterations, 2);
  EXPECT_EQ(newton.result.history.size(),
            slim.result.history.size() + std::size_t(newton.result.newton_iterations));
  const IterationStats& first = h[h.size() - std::size_t(newton.result.newton_iterations)];
  ASSERT_TRUE(first.newton);
  EXPECT_FALSE(h[h.size() - std::size_t(newton.result.newton_iterations) - 1].newton);
  std::printf(
      "SLIM %.12f in %d iterations; + %d Newton (%s) %.12f; reference %.12f; gradient "
      "%.3g -> %.3g\n",
      slim.result.history.back().energy, slim.result.history.back().iteration,
      newton.result.newton_iterations, newton.result.newton_stop_reason.c_str(), h.back().energy,
      reference, first.gradient_norm, h.back().gradient_norm);
  EXPECT_LT(h.back().energy, slim.result.history.back().energy);
  EXPECT_LE(h.back().energy, reference * (1 + 1e-9));
  EXPECT_EQ(h.back().step, 1.0);
  EXPECT_LT(h.back().gradient_norm, 0.1 * first.gradient_norm);
}
