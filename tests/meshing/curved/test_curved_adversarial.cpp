// The curved mesher on procedural adversarial surfaces (meshing/core/adversarial.hpp, issue 21):
// valid inputs that stopped it before. Each test meshes one at K = 3, ε = 1% with the default
// options and checks the result with the independent validator.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "meshing/core/adversarial.hpp"
#include "meshing/core/fiber_projection.hpp"
#include "meshing/curved/curved_mesher.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/curved/features.hpp"
#include "meshing/shell/extrusion_direction.hpp"
#include "meshing/shell/fibers_of.hpp"

using namespace curvefem;
namespace cv = curvefem::meshing::curved;

namespace {

struct Meshed {
  cv::CurvedMesh mesh;
  cv::CurvedMeshStats stats;
  cv::CurvedValidation v;
};

// The CLI's defaults at order k, ε = 1%, on one thread.
cv::CurvedMeshOptions default_options(const SurfaceMesh& input, int order) {
  cv::CurvedMeshOptions o;
  o.order = order;
  o.eps_rel = 0.01;
  o.threads = 1;
  o.feature_edges = cv::detect_feature_edges(input, 60.0);  // the CLI's default angle
  return o;
}

// Meshes `input` with `o` and validates it; prints what the tests assert, labelled.
Meshed mesh_with(const SurfaceMesh& input, const cv::CurvedMeshOptions& o, const char* label) {
  Meshed m;
  m.mesh = cv::build_curved_mesh(input, o, m.stats);
  m.v = cv::validate_curved_mesh(m.mesh.mesh, m.mesh.map, input);
  std::printf(
      "%s: %d tets, %d boundary faces, %d singular shell vertices, %d thin bisections, min scaled "
      "Jacobian %.3g, %d below 0.01, max MIPS %.3g\n",
      label, m.v.tets, m.mesh.map.boundary.num_cells(), m.stats.singular_vertices,
      m.stats.thin_splits, m.v.min_scaled_jacobian, m.v.tets_sj_below_1e2, m.v.max_mips);
  return m;
}

Meshed mesh_of(const SurfaceMesh& input, int order) {
  return mesh_with(input, default_options(input, order), "defaults");
}

}  // namespace

TEST(CurvedAdversarial, KnifeEdgedDiscWithSliversOfThreeSingularCorners) {
  // Every rim vertex singular (a 0.4° knife edge), 6 rim faces with three singular corners.
  // Before: the shell refused the slivers ("face N has three singular vertices"); without them,
  // Gmsh refused the inner surface (its knife edge folded to 0.08°, 10x sharper than the
  // input's), then two interior tets inverted (a slab's curved diagonal at a pinch stitched in as
  // their edge) and the validator counted the rim's feature edges, split at pinch points, as off
  // the boundary edges.
  const SurfaceMesh input = make_adversarial("knife_disc_slivers");
  const meshing::shell::ExtrusionDirections d =
      meshing::shell::extrusion_directions(input.V, input.F);
  ASSERT_EQ(d.singular_count, 64);
  const Meshed m = mesh_of(input, 3);
  EXPECT_TRUE(m.v.certified());
  EXPECT_TRUE(m.v.boundary_ok());
  EXPECT_EQ(m.v.features_off_edges, 0);
  EXPECT_EQ(m.v.feature_edges, 64);
  EXPECT_TRUE(m.v.valid(0.01));
  EXPECT_GT(m.stats.singular_vertices, 0);
}

TEST(CurvedAdversarial, TheThicknessGuardKeepsSlabTetsOfThinPartsFromGoingFlat) {
  // A flat cylinder (radius 1, height 0.05): its two sharp rims 2.5 ε apart. Without the guard
  // the coarsening makes cap faces far wider than the cylinder is thick, and the slab tets under
  // them go flat. Measured (K = 3, 2026-12-01): without it 100 boundary faces, min scaled
  // Jacobian 2.0e-3, 116 tets below 0.01, max MIPS 1.0e5; with the default (8 × the local
  // thickness) 228 faces, 2.2e-2, none below 0.01, max MIPS 3.0e3. With the curved edits and the
  // smoothing's scaled-Jacobian floor (2026-12-02): without the guard min scaled Jacobian 5.3e-3,
  // 27 tets below 0.01, max MIPS 2.8e4; with it 2.9e-2, none, 1.5e3. Since the edits' collapses
  // are no longer dropped by the queue (2026-12-03): without the guard 6.7e-3, 9 below, 1.4e4.
  // Since the worst-cell search may not add cells below 0.01 (2026-12-05): without the guard
  // 7.0e-3, 5 below, 1.3e4 (the search no longer pushes neighbours of its cells under 0.01).
  const SurfaceMesh input = make_adversarial("cylinder_flat");
  cv::CurvedMeshOptions o = default_options(input, 3);
  ASSERT_GT(o.max_edge_per_thickness, 0);  // on by default
  const Meshed with = mesh_with(input, o, "guard");
  o.max_edge_per_thickness = 0;
  const Meshed without = mesh_with(input, o, "without");
  const cv::CurvedValidation &a = with.v, &b = without.v;
  EXPECT_TRUE(a.valid(0.01));
  EXPECT_TRUE(b.valid(0.01));
  EXPECT_GT(a.min_scaled_jacobian, 1e-2);
  EXPECT_EQ(a.tets_sj_below_1e2, 0);
  EXPECT_LT(a.max_mips, 1e4);
  // What the guard prevents (the optimization alone does not repair it).
  EXPECT_LT(b.min_scaled_jacobian, 1e-2);
  EXPECT_GE(b.tets_sj_below_1e2, 5);
  EXPECT_GT(b.max_mips, 1e4);
  long refused = -1;
  for (const auto& [why, n] : with.stats.coarsen_rejections)
    if (why == "thickness") refused = n;
  EXPECT_GT(refused, 0);
}

TEST(CurvedAdversarial, EditSplitsRaiseTheWorstCellOfTheFlatCylinder) {
  // CurvedEditOptions::splits (off by default): measured (K = 3, 2026-12-03) 290 -> 294 tets, min
  // scaled Jacobian 0.0295 -> 0.0387, max MIPS 1.53e3 both. (This test used the sharp cylinder,
  // 0.0108 -> 0.0156, until the coarsening's flips between feature vertices raised its worst cell
  // without splits to 0.0119, a cell the splits do not improve.) Since the edits' collapses are
  // no longer dropped by the queue (CollapsesAskedForByAFlatCell... below) the cylinder's worst
  // cell is 0.0477 without splits and the splits leave it there: 276 -> 279 tets, max MIPS
  // 557 -> 500; what is left to check is that they run and make nothing worse. That holds on the
  // cylinder as the thin refinement left it at ratio 8 (the default until 2026-12-05), which this
  // test keeps; at the default ratio 3 (1,408 bisections) they make it a little worse: 310 -> 301
  // tets, min scaled Jacobian 0.0456 -> 0.0437, max MIPS 854 -> 1.1e3 (one more reason they stay
  // off by default).
  const SurfaceMesh input = make_adversarial("cylinder_flat");
  cv::CurvedMeshOptions o = default_options(input, 3);
  o.thin_refine_ratio = 8;
  ASSERT_FALSE(o.optimize.edits.splits);
  const Meshed without = mesh_with(input, o, "no splits");
  o.optimize.edits.splits = true;
  const Meshed with = mesh_with(input, o, "splits");
  EXPECT_EQ(without.stats.optimize.edits.splits, 0);
  EXPECT_GE(with.stats.optimize.edits.splits, 1);
  EXPECT_TRUE(with.v.valid(0.01));
  EXPECT_GE(with.v.min_scaled_jacobian, without.v.min_scaled_jacobian);
  EXPECT_GT(without.v.min_scaled_jacobian, 0.04);
  EXPECT_LE(with.v.max_mips, without.v.max_mips);
  // The boundary is the same, node for node.
  EXPECT_EQ(with.mesh.map.boundary.nodes, without.mesh.map.boundary.nodes);
}

TEST(CurvedAdversarial, NoisyScanWithClustersOfSingularVerticesMeshes) {
  // Radial noise of 20 edge lengths on every vertex of a level-3 icosphere: 43 singular vertices,
  // almost every edge a feature (60°). Before: the bevel's points on feature edges were collapsed
  // away by the coarsening, leaving 2 feature edges off the coarse boundary (exit 3).
  const SurfaceMesh input = make_adversarial("noise_sphere_20");
  const meshing::shell::ExtrusionDirections d =
      meshing::shell::extrusion_directions(input.V, input.F);
  ASSERT_EQ(d.singular_count, 43);
  const Meshed m = mesh_of(input, 3);
  EXPECT_GT(m.v.feature_edges, 800);
  EXPECT_EQ(m.v.features_off_edges, 0);
  EXPECT_TRUE(m.v.valid(0.01));
}

TEST(CurvedAdversarial, AMissIsRepairedOnTheCoarseShellWithoutCoarseningAgain) {
  // Spikes of 5 edge lengths on 10% of a level-3 icosphere's vertices. The curved-aware
  // coarsening's first attempt leaves 2 coarse faces beyond ε once curved (their slabs do not
  // certify fully curved after the thickening). The second attempt repairs that coarse shell
  // (splits until the missed faces' input vertices are within ε of the linear surface) instead
  // of coarsening the input again, and meets ε. Against re-coarsening (curved_repair off, the
  // behaviour before): both valid, face counts within 5%. Measured: 5 splits in 2 passes, 596 ->
  // 606 faces, against 602 re-coarsened.
  const SurfaceMesh input = make_adversarial("noise_sphere_5");
  const Meshed m = mesh_of(input, 3);
  auto has_stage = [](const cv::CurvedMeshStats& s, const std::string& name) {
    return std::any_of(s.stage_seconds.begin(), s.stage_seconds.end(),
                       [&](const auto& e) { return e.first == name; });
  };
  EXPECT_EQ(m.stats.curved_attempts, 2);
  EXPECT_EQ(m.stats.curved_repairs, 1);
  EXPECT_EQ(m.stats.repair_failures, 0);
  EXPECT_GT(m.stats.repair_splits, 0);
  EXPECT_TRUE(has_stage(m.stats, "discarded attempt 1"));
  EXPECT_TRUE(has_stage(m.stats, "repair"));
  EXPECT_FALSE(has_stage(m.stats, "coarsen")) << "the kept attempt did not coarsen the input";
  EXPECT_TRUE(m.v.valid(0.01));
  EXPECT_LE(m.v.max_distance_rel, 0.01);

  cv::CurvedMeshOptions o = default_options(input, 3);
  o.curved_repair = false;
  cv::CurvedMeshStats again;
  const cv::CurvedMesh r = cv::build_curved_mesh(input, o, again);
  EXPECT_TRUE(cv::validate_curved_mesh(r.mesh, r.map, input).valid(0.01));
  EXPECT_EQ(again.curved_repairs, 0);
  EXPECT_TRUE(has_stage(again, "coarsen"));
  std::printf("repaired: %d faces by %d splits; coarsened again: %d faces\n", m.stats.coarse_faces,
              m.stats.repair_splits, again.coarse_faces);
  EXPECT_LE(m.stats.coarse_faces, 1.05 * again.coarse_faces);
}

TEST(CurvedAdversarial, TheLinearPhaseRunBesideTheFirstAttemptGivesTheSameMesh) {
  // On two threads the two-phase coarsening's linear phase starts beside the first attempt
  // (CurvedMeshOptions::concurrent_linear_phase). noise_sphere_5's first attempt misses ε once
  // curved; without the repair the linear phase is needed and is waited for; with it (the
  // default) the repair holds and the linear phase is cancelled. Either way the mesh must be
  // bit-identical to the one of the serial order (the linear phase run only once needed).
  const SurfaceMesh input = make_adversarial("noise_sphere_5");
  auto same = [](const cv::CurvedMesh& a, const cv::CurvedMesh& b) {
    return a.mesh.nodes.rows() == b.mesh.nodes.rows() &&
           a.mesh.cells.rows() == b.mesh.cells.rows() && a.mesh.nodes == b.mesh.nodes &&
           a.mesh.cells == b.mesh.cells && a.mesh.cell_tags == b.mesh.cell_tags &&
           a.map.vertex_face == b.map.vertex_face && a.map.vertex_uv == b.map.vertex_uv;
  };
  for (const bool repair : {false, true}) {
    cv::CurvedMeshOptions o = default_options(input, 3);
    o.threads = 2;
    o.curved_repair = repair;
    o.concurrent_linear_phase = true;
    const Meshed beside =
        mesh_with(input, o, repair ? "repair, concurrent" : "no repair, concurrent");
    o.concurrent_linear_phase = false;
    const Meshed serial = mesh_with(input, o, repair ? "repair, serial" : "no repair, serial");
    EXPECT_TRUE(beside.stats.linear_phase_concurrent);
    EXPECT_FALSE(serial.stats.linear_phase_concurrent);
    EXPECT_GE(beside.stats.curved_attempts, 2) << "the first attempt must miss for this test";
    EXPECT_TRUE(same(beside.mesh, serial.mesh)) << (repair ? "with" : "without") << " the repair";
    EXPECT_EQ(beside.stats.coarse_faces, serial.stats.coarse_faces);
    EXPECT_EQ(beside.stats.linear_phase_faces, serial.stats.linear_phase_faces);
    if (repair) {
      EXPECT_EQ(beside.stats.linear_phase_faces, 0) << "the repair held: cancelled, not used";
    } else {
      EXPECT_GT(beside.stats.linear_phase_faces, 0) << "used";
      EXPECT_GT(beside.stats.linear_phase_seconds, 0);
    }
    EXPECT_TRUE(beside.v.valid(0.01));
  }
  // Above the size limit (memory) it is not started.
  cv::CurvedMeshOptions o = default_options(input, 3);
  o.threads = 2;
  o.concurrent_linear_phase_max_faces = 10;
  cv::CurvedMeshStats stats;
  cv::build_curved_mesh(input, o, stats);
  EXPECT_FALSE(stats.linear_phase_concurrent);
}

TEST(CurvedAdversarial, ABarWhoseInputEdgesAreFarLongerThanItIsThickIsRefinedFirst) {
  // A 1 x 0.02 x 0.02 bar, 4 x 4 quads per side: its sides are needle triangles 0.25 long,
  // 12-18 times the bar's thickness, and the thickness guard can only refuse collapses, not add
  // vertices. The thin-part refinement bisects the input's thin edges (not its 12 feature
  // edges) before the shell. Measured (K = 3, 2026-12-02): without it 181 tets, min scaled
  // Jacobian 5.6e-4, 154 tets (85%) below 0.01, max MIPS 3.5e4; with it (112 bisections of 128
  // input faces) 72 tets, 9.0e-3, 16 below 0.01, max MIPS 2.4e3. Both under the strict shape
  // guard, which this test keeps: the shape slack (on by default since 2026-12-03) lets the
  // unrefined bar's needle sides coarsen by itself (24 tets, 8.9e-3, 16 below 0.01, max MIPS
  // 1.9e3), and the refined bar then ends with 82 tets, 4.3e-3, 17 below 0.01, max MIPS 4.2e3.
  // At the default ratio 3 with the closure (2026-12-05): 1,040 bisections, 75 tets, 4.2e-3, 16
  // below 0.01, max MIPS 3.1e3; without the refinement 172 tets, 5.7e-4, 154 below, 2.5e4.
  // The shape refinement (on by default since 2026-12-04) is off here: it refines this bar's
  // needle sides by itself (CurvedAdversarial.NeedleSidesOfABarAreRefinedForTheirShape).
  const SurfaceMesh input = make_adversarial("box_thin_long");
  cv::CurvedMeshOptions o = default_options(input, 3);
  o.shape_slack = 0;
  o.shape_refine = 0;
  ASSERT_GT(o.thin_refine_ratio, 0);  // on by default
  const Meshed with = mesh_with(input, o, "refined");
  o.thin_refine_ratio = 0;
  const Meshed without = mesh_with(input, o, "without");
  const cv::CurvedValidation &a = with.v, &b = without.v;
  const cv::CurvedMeshStats &with_stats = with.stats, &without_stats = without.stats;
  EXPECT_TRUE(a.valid(0.01));
  EXPECT_TRUE(b.valid(0.01));
  EXPECT_GT(with_stats.thin_splits, 50);
  // At ratio 3 the refinement has more (shorter) thin edges after than before; the worst is lower.
  EXPECT_LT(with_stats.thin_max_ratio_after, with_stats.thin_max_ratio_before);
  EXPECT_TRUE(with_stats.thin_fallback.empty());
  EXPECT_EQ(without_stats.thin_splits, 0);
  EXPECT_EQ(a.feature_edges, 48);  // the feature chains still hold: none was bisected
  EXPECT_EQ(a.features_off_edges, 0);
  // What the refinement buys.
  EXPECT_GT(a.min_scaled_jacobian, 5 * b.min_scaled_jacobian);
  EXPECT_LT(a.tets_sj_below_1e2 * 3, b.tets_sj_below_1e2);
  EXPECT_LT(a.max_mips * 5, b.max_mips);
}

TEST(CurvedAdversarial, NeedleSidesOfABarAreRefinedForTheirShape) {
  // The same bar with the default options: the shape refinement bisects every input face with a
  // 2-D MIPS above 20 whose longest edge is longer than 8 ε (its sides' needles, feature edges
  // included), so the coarsening has vertices inside the bar's faces and along its edges.
  const SurfaceMesh input = make_adversarial("box_thin_long");
  cv::CurvedMeshOptions o = default_options(input, 3);
  ASSERT_GT(o.shape_refine, 0);  // on by default
  const Meshed with = mesh_with(input, o, "shape-refined");
  o.shape_refine = 0;
  const Meshed without = mesh_with(input, o, "not shape-refined");
  const cv::CurvedValidation &a = with.v, &b = without.v;
  std::printf(
      "bar, shape refinement: %d poor faces, %d bisections (%d on feature edges); min sJ "
      "%.3g vs %.3g, below 0.01 %d vs %d, max MIPS %.3g vs %.3g, tets %d vs %d\n",
      with.stats.shape_poor_before, with.stats.shape_splits, with.stats.shape_feature_splits,
      a.min_scaled_jacobian, b.min_scaled_jacobian, a.tets_sj_below_1e2, b.tets_sj_below_1e2,
      a.max_mips, b.max_mips, a.tets, b.tets);
  EXPECT_TRUE(a.valid(0.01));
  EXPECT_TRUE(b.valid(0.01));
  EXPECT_GT(with.stats.shape_splits, 0);
  EXPECT_GT(with.stats.shape_feature_splits, 0);
  EXPECT_EQ(with.stats.shape_poor_after, 0);
  EXPECT_EQ(without.stats.shape_splits, 0);
  EXPECT_EQ(a.feature_edges, 48);  // the input's feature edges, each along the boundary's edges
  EXPECT_EQ(a.features_off_edges, 0);
  EXPECT_TRUE(with.stats.thin_fallback.empty());
  EXPECT_GT(a.min_scaled_jacobian, 2 * b.min_scaled_jacobian);
  EXPECT_LT(a.max_mips * 2, b.max_mips);
  // φ⁻¹ by the saved fibers, which cross the refined surface (Shell::refinement), brings every
  // input vertex's image back to it.
  ASSERT_FALSE(with.mesh.shell.refinement.empty());
  const curvefem::FiberProjection fibers(
      curvefem::meshing::shell::fibers_of(with.mesh.shell, input), input);
  const double unit = (input.V.colwise().maxCoeff() - input.V.colwise().minCoeff()).maxCoeff();
  int missed = 0;
  double worst = 0;
  for (int v = 0; v < with.mesh.map.num_input_vertices(); ++v) {
    const auto c = fibers.project(with.mesh.map.vertex_face[v], with.mesh.map.vertex_uv(v, 0),
                                  with.mesh.map.vertex_uv(v, 1));
    if (!c)
      ++missed;
    else
      worst = std::max(worst, (c->position - input.V.row(v).transpose()).norm() / unit);
  }
  EXPECT_EQ(missed, 0);
  EXPECT_LE(worst, 1e-12);
}

TEST(CurvedAdversarial, TheThinSplitRingMeshesAtOrderFour) {
  // A ring whose wall is 0.5 ε thick, cut by a 0.1 ε slit. Before (robustness.md): exit 3 on an
  // input `check` accepts, at K = 3 (Gmsh refused the inner surface at every slab depth) and at
  // K = 4 (a linear slab in the slit, positive by the shell's exact test, left undecided by the
  // floating-point certificate at order 4: "the linear slab of coarse face 528 is not certified
  // positive"). Now the wall is thin-refined first and such a slab is left to the thickening,
  // which deepens it and certifies it. Measured (2026-12-02), with the thin refinement of then
  // (no longest-edge closure, no shape check): 5,186 bisections of 384 input faces, 4,601 tets,
  // min scaled Jacobian 1.25e-2, none below 0.01, max MIPS 7.4e3, and undecided slabs deferred.
  // With the closure (2026-12-05): 4,596 bisections, 4,785 tets, min 2.05e-2, none below 0.01,
  // max MIPS 5.8e3, and no slab undecided. The refinement of before still runs below, so the
  // deferral of undecided slabs keeps a test.
  const SurfaceMesh input = make_adversarial("split_ring_thin");
  for (const bool closure : {true, false}) {
    SCOPED_TRACE(closure ? "closure" : "the refinement of before");
    cv::CurvedMeshOptions o = default_options(input, 4);
    o.threads = 2;
    o.thin_refine_closure = closure;
    o.thin_refine_child_mips = closure ? 20 : 0;
    const Meshed m = mesh_with(input, o, closure ? "split ring" : "split ring, old refinement");
    const cv::CurvedValidation& v = m.v;
    const cv::CurvedMeshStats& stats = m.stats;
    std::printf("%d deferred undecided slabs\n", stats.curve_deferred_undecided);
    EXPECT_TRUE(v.valid(0.01));
    EXPECT_TRUE(stats.thin_fallback.empty());
    EXPECT_GT(stats.thin_splits, 1000);
    if (!closure) EXPECT_GT(stats.curve_deferred_undecided, 0);
    EXPECT_GT(v.min_scaled_jacobian, closure ? 1.5e-2 : 1e-3);
    EXPECT_LE(v.tets_sj_below_1e2, v.tets / 100);
  }
}

TEST(CurvedAdversarial, EdgesBetweenFeatureVerticesThatAreNotFeatureEdgesMayFlip) {
  // The coarsening's flips refused every edge between two frozen vertices, as if it were a
  // feature edge; with feature chains the coarse feature edges are marked, so only those are
  // kept. On the sharp box the diagonals between the corners (all frozen) could not flip before.
  // Measured (K = 3, 2026-12-03): 48 -> 34 tets, min scaled Jacobian 0.105 -> 0.152, max MIPS
  // 146 -> 80 (106 since the curved edits' collapses are no longer dropped, 34 -> 29 tets, min
  // scaled Jacobian 0.157). On the dev meshes (benchmarks/results/robustness_flips.md) anchor's
  // tets below 0.01 went 17 -> 4 and abc_00000008's worst coarse cap (0.07°) went.
  const SurfaceMesh input = make_adversarial("box_sharp");
  const Meshed m = mesh_of(input, 3);
  EXPECT_TRUE(m.v.valid(0.01));
  EXPECT_EQ(m.v.features_off_edges, 0);
  EXPECT_GT(m.v.feature_edges, 0);
  EXPECT_EQ(m.mesh.map.boundary.num_cells(), 12);
  EXPECT_GE(m.v.min_scaled_jacobian, 0.14);
  EXPECT_LE(m.v.max_mips, 110.0);
  EXPECT_LE(m.v.tets, 40);
}

TEST(CurvedAdversarial, CollapsesAskedForByAFlatCellAreNotDroppedByTheQueue) {
  // The curved edits queue a collapse of every edge of a target cell, but the queue's stale
  // filter judged each entry by the cell its edge tuple happened to name, usually not the target,
  // so most of them were dropped unseen; now a collapse is judged by the star of the vertex it
  // removes. With the curved-MIPS guards of the edits and the smoothing, measured (K = 3,
  // 2026-12-03) on the thin long box: 82 -> 84 tets, below 0.01 17 -> 13, min scaled Jacobian
  // 0.00428 -> 0.00507, max MIPS 4173 -> 1533.
  const SurfaceMesh input = make_adversarial("box_thin_long");
  const Meshed m = mesh_of(input, 3);
  EXPECT_TRUE(m.v.valid(0.01));
  EXPECT_GT(m.v.min_scaled_jacobian, 0.0048);
  EXPECT_LE(m.v.tets_sj_below_1e2, 14);
  EXPECT_LE(m.v.max_mips, 2000.0);
}

TEST(CurvedAdversarial, FeatureCurvesAreDroppedByTheExtentOfTheirComponentAndTheLocalBound) {
  // Three components: a unit square loop, a 0.05-long path and a single 0.15-long edge.
  SurfaceMesh m;
  m.V.resize(9, 3);
  m.V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,  // square
      5, 5, 5, 5.03, 5, 5, 5.03, 5.04, 5,     // path: bbox diagonal 0.05
      9, 9, 9, 9.15, 9, 9;                    // edge: 0.15
  const std::vector<std::array<int, 2>> edges = {{0, 1}, {1, 2}, {2, 3}, {0, 3},
                                                 {4, 5}, {5, 6}, {7, 8}};
  int dropped = -1;
  auto kept = cv::drop_small_feature_components(m, edges, 0.1, {}, &dropped);
  EXPECT_EQ(dropped, 1);
  EXPECT_EQ(kept, (std::vector<std::array<int, 2>>{{0, 1}, {1, 2}, {2, 3}, {0, 3}, {7, 8}}));
  kept = cv::drop_small_feature_components(m, edges, 0.2, {}, &dropped);
  EXPECT_EQ(dropped, 2);
  EXPECT_EQ(kept.size(), 4u);
  // A smaller local bound at one vertex of a component keeps the whole component.
  std::vector<double> scale(9, 1.0);
  scale[5] = 0.4;  // path: 0.1 x 0.4 = 0.04 < 0.05
  kept = cv::drop_small_feature_components(m, edges, 0.1, scale, &dropped);
  EXPECT_EQ(dropped, 0);
  EXPECT_EQ(kept.size(), edges.size());
  kept = cv::drop_small_feature_components(m, edges, 1e9, {}, &dropped);
  EXPECT_EQ(dropped, 3);
  EXPECT_TRUE(kept.empty());
}

TEST(CurvedAdversarial, OpenEndsOfFeatureCurvesAreCutBackByArcLengthUpToJunctions) {
  // A closed square (untouched), an open path of ten 0.1 edges (vertices 4..14), and a star of
  // three paths from junction 15: 2, 5 and 5 edges of 0.1.
  SurfaceMesh m;
  std::vector<Eigen::Vector3d> P = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (int i = 0; i <= 10; ++i) P.push_back({5 + 0.1 * i, 0, 0});  // 4..14
  P.push_back({9, 9, 9});                                          // 15: junction
  for (int i = 1; i <= 2; ++i) P.push_back({9 + 0.1 * i, 9, 9});   // 16, 17
  for (int i = 1; i <= 5; ++i) P.push_back({9, 9 + 0.1 * i, 9});   // 18..22
  for (int i = 1; i <= 5; ++i) P.push_back({9, 9, 9 + 0.1 * i});   // 23..27
  m.V.resize(Eigen::Index(P.size()), 3);
  for (std::size_t i = 0; i < P.size(); ++i) m.V.row(Eigen::Index(i)) = P[i].transpose();
  std::vector<std::array<int, 2>> edges = {{0, 1}, {1, 2}, {2, 3}, {0, 3}};
  for (int i = 4; i < 14; ++i) edges.push_back({i, i + 1});
  edges.push_back({15, 16}), edges.push_back({16, 17});
  edges.push_back({15, 18});
  for (int i = 18; i < 22; ++i) edges.push_back({i, i + 1});
  edges.push_back({15, 23});
  for (int i = 23; i < 27; ++i) edges.push_back({i, i + 1});
  auto has = [](const std::vector<std::array<int, 2>>& es, int a, int b) {
    return std::find(es.begin(), es.end(), std::array<int, 2>{a, b}) != es.end();
  };
  int ends = -1;
  // 0.25: three edges (0.3) from each end of the path and of the star's long arms; the short
  // arm (0.2) goes whole, up to the junction, which then joins the two others.
  auto kept = cv::trim_feature_ends(m, edges, 0.25, {}, &ends);
  EXPECT_EQ(ends, 5);
  EXPECT_EQ(kept.size(), edges.size() - 3 - 3 - 2 - 3 - 3);
  for (int i = 7; i < 11; ++i) EXPECT_TRUE(has(kept, i, i + 1)) << i;  // the path's middle
  EXPECT_FALSE(has(kept, 6, 7));
  EXPECT_FALSE(has(kept, 11, 12));
  EXPECT_FALSE(has(kept, 15, 16));
  EXPECT_TRUE(has(kept, 15, 18) && has(kept, 18, 19) && !has(kept, 19, 20));
  for (const auto& e : std::vector<std::array<int, 2>>{{0, 1}, {1, 2}, {2, 3}, {0, 3}})
    EXPECT_TRUE(has(kept, e[0], e[1]));  // closed curve
  // A smaller local bound at one end cuts less there: 0.25 x 0.3 = 0.075, one edge.
  std::vector<double> scale(P.size(), 1.0);
  scale[4] = 0.3;
  kept = cv::trim_feature_ends(m, edges, 0.25, scale, &ends);
  EXPECT_FALSE(has(kept, 4, 5));
  EXPECT_TRUE(has(kept, 5, 6));
  // Cut back by more than its length, an open curve goes whole, from its first end.
  kept = cv::trim_feature_ends(m, edges, 5.0, {}, &ends);
  EXPECT_EQ(kept.size(), 4u);
  EXPECT_EQ(cv::trim_feature_ends(m, edges, 0.0, {}, &ends), edges);
  EXPECT_EQ(ends, 0);
}

TEST(CurvedAdversarial, SpikesSmallerThanEpsAreNotKeptAsFeaturesUnlessAskedFor) {
  // Six sharp spikes 0.6 ε across and 0.7 ε high on a box: their rims and ridges are feature
  // curves ending in corners, which no collapse may move. Dropped (the default, 2 ε), the
  // coarsening flattens them within ε; kept, every spike stays exactly.
  const SurfaceMesh input = make_adversarial("box_small_spikes");
  const cv::CurvedMeshOptions o = default_options(input, 3);
  ASSERT_EQ(o.feature_edges.size(), 228u);  // 192 box edges, 6 x 6 spike edges
  const Meshed dropped = mesh_with(input, o, "small features dropped");
  EXPECT_EQ(dropped.stats.small_feature_curves, 6);
  EXPECT_EQ(dropped.stats.small_feature_edges, 36);
  EXPECT_EQ(dropped.v.feature_edges, 192);
  EXPECT_EQ(dropped.v.features_off_edges, 0);
  EXPECT_TRUE(dropped.v.valid(0.01));
  EXPECT_GT(dropped.v.max_distance_rel, 1e-3);  // the spikes are flattened, not kept
  cv::CurvedMeshOptions all = o;
  all.feature_min_size = 0;
  const Meshed kept = mesh_with(input, all, "every feature kept");
  EXPECT_EQ(kept.stats.small_feature_curves, 0);
  EXPECT_EQ(kept.v.feature_edges, 228);
  EXPECT_EQ(kept.v.features_off_edges, 0);
  EXPECT_TRUE(kept.v.valid(0.01));
  EXPECT_LT(kept.v.max_distance_rel, 1e-9);  // every spike vertex is a frozen corner
  EXPECT_LT(dropped.mesh.map.boundary.num_cells(), kept.mesh.map.boundary.num_cells());
}

TEST(CurvedAdversarial, TheWorstCellSearchAddsNoTetsBelowTheFlatBar) {
  // The knife disc's rim band is flat whatever the mesher does (a 0.5° wedge thinner than ε):
  // the search for the worst cells raises star minima there, and before OptimizeOptions::
  // worst_flat it did so by pushing neighbours under 0.01 (415 -> 427 tets below 0.01 of 1,273
  // at K = 3 in the corpus run). With it: no more tets below 0.01 than without the search, and
  // the worst cell no lower.
  const SurfaceMesh input = make_adversarial("knife_disc");
  cv::CurvedMeshOptions off = default_options(input, 3);
  off.optimize.worst_sweeps = 0;
  const Meshed without = mesh_with(input, off, "no worst-cell search");
  const Meshed with = mesh_of(input, 3);
  ASSERT_TRUE(with.v.valid(0.01));
  ASSERT_TRUE(without.v.valid(0.01));
  EXPECT_GT(with.stats.optimize.worst_moves, 0);
  EXPECT_LE(with.v.tets_sj_below_1e2, without.v.tets_sj_below_1e2);
  EXPECT_GE(with.v.min_scaled_jacobian, without.v.min_scaled_jacobian);
}

TEST(CurvedAdversarial, TheWorstMipsSearchLowersANearFlatCellTheScaledJacobianMisses) {
  // A plate half as thick as ε: at K = 3 its worst cell has curved MIPS 1.03e4 (above the quality
  // goal's 1e4) at a sampled scaled Jacobian of 0.027, above the worst-cell search's 0.02, so
  // only OptimizeOptions::worst_mips visits it (measured: 1.03e4 -> 9.2e3, 7 moves).
  const SurfaceMesh input = make_adversarial("thin_plate_05");
  cv::CurvedMeshOptions off = default_options(input, 3);
  off.optimize.worst_mips = 0;
  const Meshed without = mesh_with(input, off, "no MIPS search");
  const Meshed with = mesh_of(input, 3);  // the default: above 2000, 100 stars a sweep
  ASSERT_TRUE(with.v.valid(0.01));
  ASSERT_TRUE(without.v.valid(0.01));
  EXPECT_EQ(without.stats.optimize.worst_mips_visits, 0);
  EXPECT_GT(with.stats.optimize.worst_mips_moves, 0);
  EXPECT_GT(without.v.max_mips, 1e4);
  EXPECT_LT(with.v.max_mips, 0.95 * without.v.max_mips);
  EXPECT_LT(with.stats.optimize.worst_mips_after, with.stats.optimize.worst_mips_before);
  // The scaled Jacobians stay above min(before, 0.02): the worst cell is no lower.
  EXPECT_GE(with.v.min_scaled_jacobian, std::min(without.v.min_scaled_jacobian, 0.02));
  EXPECT_LE(with.v.tets_sj_below_1e2, without.v.tets_sj_below_1e2);
}

TEST(CurvedAdversarial, DistortedCurvedPatchesAreFlattenedUntilTheirAreaElementRecovers) {
  // Radial noise of 2 edges tilts the pillars so far that some fibers cross the input far apart:
  // the fully curved patch of a face that does not need it is bunched to one side or folds over
  // (its normal turns against its linear triangle's). Certified and within ε, but its slab tets
  // are flat on the boundary: the worst curved MIPS of the mesh, 5.8e4, sat on a patch whose area
  // element fell to 1.6% of its largest. The distortion floor lowers those faces' α; the
  // validator counts folded patches independently from the final boundary.
  const SurfaceMesh input = make_adversarial("noise_sphere_2");
  cv::CurvedMeshOptions off = default_options(input, 3);
  off.curve_distortion_floor = 0;
  const Meshed without = mesh_with(input, off, "no distortion floor");
  const Meshed with = mesh_of(input, 3);
  ASSERT_TRUE(without.v.valid(0.01));
  ASSERT_TRUE(with.v.valid(0.01));
  std::printf("folded patches: mesher %d -> %d (lowered %d), validator %d -> %d\n",
              with.stats.folded_faces_before, with.stats.folded_faces_after,
              with.stats.faces_lowered_for_distortion, without.v.boundary_faces_folded,
              with.v.boundary_faces_folded);
  // Off, nothing is counted or lowered; the validator sees the folds (37 measured).
  EXPECT_EQ(without.stats.faces_lowered_for_distortion, 0);
  EXPECT_GT(without.v.boundary_faces_folded, 20);
  // On: the folds are undone (1 is left; 7 before neighbours joined the steps).
  EXPECT_GT(with.stats.folded_faces_before, 20);
  EXPECT_GT(with.stats.faces_lowered_for_distortion, 20);
  EXPECT_LE(with.stats.folded_faces_after, 3);
  EXPECT_LE(with.v.boundary_faces_folded, 3);
  EXPECT_LT(with.v.boundary_faces_distorted, without.v.boundary_faces_distorted / 2);
  // What it is for (measured 5.8e4 -> 2.4e3, 1.9e-3 -> 1.5e-2): the quality goal's bounds.
  EXPECT_LT(with.v.max_mips, 1e4);
  EXPECT_GT(without.v.max_mips, 1e4);
  EXPECT_GE(with.v.min_scaled_jacobian, 1e-3);
  EXPECT_LT(with.v.mean_mips, without.v.mean_mips);
}
