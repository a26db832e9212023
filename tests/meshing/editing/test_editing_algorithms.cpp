// The algorithms written on the editing framework reach their targets on generated shapes, with
// 1 and 2 threads, and never violate their invariants; the data tests run them on real meshes.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "meshing/core/primitives.hpp"
#include "meshing/editing/algorithms/harmonic_triangulation.hpp"
#include "meshing/editing/algorithms/surface_edit_mesh.hpp"
#include "meshing/editing/algorithms/surface_remeshing.hpp"
#include "meshing/io/surface_io.hpp"
#include "tests/support/test_support.hpp"

namespace ed = curvefem::meshing::editing;
using curvefem::SurfaceMesh;

namespace {

// Closed, edge-manifold and consistently oriented (load throws otherwise); Euler characteristic.
long euler_characteristic(const SurfaceMesh& s) {
  ed::SurfaceEditMesh m;
  m.load(s);
  EXPECT_EQ(m.check_connectivity(), "");
  return long(m.num_vertices()) - long(m.get_edges().size()) + long(m.num_cells());
}

// Every face of a star-shaped surface around the origin faces outward (no fold).
bool all_faces_outward(const SurfaceMesh& s) {
  for (int f = 0; f < s.num_faces(); ++f) {
    const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    if ((b - a).cross(c - a).dot((a + b + c) / 3.0) <= 0) return false;
  }
  return true;
}

double sphere_volume_error(const SurfaceMesh& s) {
  return std::abs(curvefem::signed_volume(s) - 4.0 / 3.0 * std::numbers::pi) /
         (4.0 / 3.0 * std::numbers::pi);
}

}  // namespace

class CollapseThreads : public ::testing::TestWithParam<std::tuple<ed::RemeshAlgorithm, int>> {};

TEST_P(CollapseThreads, ReachesTheFaceBudgetWithoutFolds) {
  const auto [algorithm, threads] = GetParam();
  const SurfaceMesh sphere = curvefem::make_icosphere(4);  // 5120 faces
  ed::RemeshOptions o;
  o.algorithm = algorithm;
  o.target_faces = 800;
  o.threads = threads;
  const ed::RemeshResult r = ed::remesh(sphere, o);
  // Each collapse removes two faces; in parallel each task may finish one collapse past the
  // budget.
  EXPECT_LE(r.mesh.num_faces(), 800);
  EXPECT_GE(r.mesh.num_faces(), 800 - 2 * threads);
  EXPECT_EQ(euler_characteristic(r.mesh), 2);
  EXPECT_TRUE(all_faces_outward(r.mesh));
  EXPECT_LT(sphere_volume_error(r.mesh), 0.05);
  ASSERT_EQ(r.passes.size(), 1u);
  const ed::PassStats& s = r.passes[0].second;
  EXPECT_EQ(s.attempted, s.succeeded + s.rejected());
  EXPECT_EQ(s.succeeded, std::size_t(5120 - r.mesh.num_faces()) / 2);
  EXPECT_EQ(s.threads, threads);
}

INSTANTIATE_TEST_SUITE_P(
    Editing, CollapseThreads,
    ::testing::Combine(::testing::Values(ed::RemeshAlgorithm::shortest_collapse,
                                         ed::RemeshAlgorithm::qslim),
                       ::testing::Values(1, 2)),
    [](const auto& info) {
      const bool q = std::get<0>(info.param) == ed::RemeshAlgorithm::qslim;
      return std::string(q ? "qslim" : "shortest") + "_threads" +
             std::to_string(std::get<1>(info.param));
    });

TEST(EditingAlgorithms, QSlimSimplifiesABoxExactly) {
  // Planar faces have zero quadric error: QSlim must reach a tiny budget without moving the
  // surface at all (corners are where three planes meet, the optimal placement).
  const SurfaceMesh box = curvefem::make_box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 3), 6);
  for (int threads : {1, 2}) {
    ed::RemeshOptions o;
    o.algorithm = ed::RemeshAlgorithm::qslim;
    o.target_faces = 40;
    o.threads = threads;
    const ed::RemeshResult r = ed::remesh(box, o);
    EXPECT_LE(r.mesh.num_faces(), 40) << threads << " threads";
    const ed::SurfaceQuality q = ed::measure_quality(r.mesh, box);
    EXPECT_LT(q.max_deviation, 1e-9) << threads << " threads";
    EXPECT_LT(q.max_deviation_from_reference, 1e-9) << threads << " threads";
    EXPECT_NEAR(curvefem::signed_volume(r.mesh), 6.0, 1e-9);
  }
}

TEST(EditingAlgorithms, IsotropicRemeshingReachesTheTargetLength) {
  const SurfaceMesh sphere = curvefem::make_icosphere(4);  // edges ~0.07
  for (int threads : {1, 2}) {
    ed::RemeshOptions o;
    o.algorithm = ed::RemeshAlgorithm::isotropic;
    o.target_edge = 0.15;
    o.threads = threads;
    const ed::RemeshResult r = ed::remesh(sphere, o);
    const ed::SurfaceQuality q = ed::measure_quality(r.mesh, sphere);
    EXPECT_NEAR(q.mean_edge, 0.15, 0.15 * 0.15) << threads << " threads";
    // Splits bound edges by 4/3 L; flips and smoothing afterwards may stretch a few a little.
    EXPECT_LE(q.max_edge, 1.6 * 0.15);
    EXPECT_GT(q.min_angle_deg, 25.0);
    std::size_t total = 0;
    for (const auto& [valence, count] : q.valence_histogram) total += count;
    EXPECT_GT(double(q.valence_histogram.at(6)) / double(total), 0.6);
    EXPECT_LT(q.max_deviation, 0.01);  // vertices are projected back onto the input
    EXPECT_EQ(euler_characteristic(r.mesh), 2);
    EXPECT_TRUE(all_faces_outward(r.mesh));
  }
}

TEST(EditingAlgorithms, EnvelopeIsNeverLeft) {
  // A torus decimated as far as possible inside an envelope of 1% of its size: the measured
  // deviation (independent sampling) stays below ε although the budget cannot be reached.
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.35, 64, 32);
  const double eps = 0.01 * 2.7;
  for (auto algorithm : {ed::RemeshAlgorithm::shortest_collapse, ed::RemeshAlgorithm::qslim}) {
    ed::RemeshOptions o;
    o.algorithm = algorithm;
    o.target_faces = 100;
    o.envelope = eps;
    o.threads = 2;
    const ed::RemeshResult r = ed::remesh(torus, o);
    const ed::SurfaceQuality q = ed::measure_quality(r.mesh, torus);
    EXPECT_LE(q.max_deviation, eps);
    EXPECT_GT(r.mesh.num_faces(), 100);  // the envelope stopped it
    EXPECT_LT(r.mesh.num_faces(), torus.num_faces() / 3);
    EXPECT_EQ(euler_characteristic(r.mesh), 0);
    EXPECT_GT(r.passes[0].second.rejected_invariant, 0u);
  }
  // Without the envelope the same budget is reached and the deviation is far larger.
  ed::RemeshOptions o;
  o.target_faces = 100;
  const ed::RemeshResult free = ed::remesh(torus, o);
  EXPECT_LE(free.mesh.num_faces(), 100);
  EXPECT_GT(ed::measure_quality(free.mesh, torus).max_deviation, 4 * eps);
}

TEST(EditingAlgorithms, BadInputIsRejected) {
  SurfaceMesh bad = curvefem::make_icosphere(1);
  std::swap(bad.F(0, 1), bad.F(0, 2));  // one face flipped
  ed::RemeshOptions o;
  o.target_faces = 10;
  EXPECT_THROW(ed::remesh(bad, o), curvefem::InputError);
  o.target_faces = 0;
  EXPECT_THROW(ed::remesh(curvefem::make_icosphere(1), o), curvefem::InputError);
}

TEST(EditingAlgorithms, HarmonicTriangulationRemovesSlivers) {
  std::mt19937 rng(2019);
  std::uniform_real_distribution<double> u(0, 1);
  Eigen::MatrixXd points(600, 3);
  for (int i = 0; i < points.rows(); ++i) points.row(i) << u(rng), u(rng), u(rng);
  for (int threads : {1, 2}) {
    ed::HarmonicOptions o;
    o.threads = threads;
    const ed::HarmonicResult r = ed::harmonic_triangulation(points, o);
    EXPECT_LT(r.after.mean_harmonic_index, r.before.mean_harmonic_index);
    EXPECT_LT(r.after.max_harmonic_index, r.before.max_harmonic_index);
    EXPECT_LT(r.after.slivers, r.before.slivers);
    EXPECT_GT(r.passes[0].second.succeeded, 50u);
    // Flips keep the convex hull: same volume; every tet positive.
    EXPECT_NEAR(r.after.volume, r.before.volume, 1e-12);
    for (int t = 0; t < r.T.rows(); ++t) {
      const Eigen::Vector3d a = r.V.row(r.T(t, 0)), b = r.V.row(r.T(t, 1)), c = r.V.row(r.T(t, 2)),
                            d = r.V.row(r.T(t, 3));
      ASSERT_GT((b - a).cross(c - a).dot(d - a), 0.0);
    }
    ed::TetMesh check;
    std::vector<ed::TetMesh::Cell> cells;
    for (int t = 0; t < r.T.rows(); ++t)
      cells.push_back({ed::Id(r.T(t, 0)), ed::Id(r.T(t, 1)), ed::Id(r.T(t, 2)), ed::Id(r.T(t, 3))});
    check.initialize(std::size_t(r.V.rows()), cells);
    EXPECT_EQ(check.check_connectivity(), "");
  }
}
