// Real meshes (data label): curved meshes of small dev meshes pass the independent validator.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <optional>

#include "meshing/curved/curved_mesher.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/curved/features.hpp"
#include "meshing/io/surface_io.hpp"
#include "tests/support/test_support.hpp"

namespace cv = curvefem::meshing::curved;

namespace {
// A dev mesh of ../shared/data (nullopt when the data is absent: the caller skips), its options
// at K = 3, ε = 1%, 2 threads, features above 60°.
struct DevRun {
  curvefem::SurfaceMesh input;
  cv::CurvedMeshOptions options;
};
std::optional<DevRun> dev_mesh(const char* file) {
  const auto dir = curvefem::test::shared_data_dir();
  if (!dir) return std::nullopt;
  DevRun r;
  r.input = curvefem::io::read_surface(*dir / "dev" / file);
  r.options.order = 3;
  r.options.eps_rel = 1e-2;
  r.options.threads = 2;
  r.options.feature_edges = cv::detect_feature_edges(r.input, 60);
  return r;
}
constexpr const char* k_no_data = "../shared/data not found: real-mesh curved test skipped";
}  // namespace

struct DataCase {
  const char* file;
  double max_face_ratio;  // boundary faces / input faces the coarsening must reach
};
class CurvedData : public ::testing::TestWithParam<DataCase> {};

TEST_P(CurvedData, ValidatorAcceptsTheCurvedMesh) {
  auto run = dev_mesh(GetParam().file);
  if (!run) GTEST_SKIP() << k_no_data;
  const curvefem::SurfaceMesh& input = run->input;
  cv::CurvedMeshOptions& o = run->options;
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh m = cv::build_curved_mesh(input, o, stats);
  const cv::CurvedValidation v = cv::validate_curved_mesh(m.mesh, m.map, input);
  EXPECT_TRUE(v.certified()) << v.non_positive_tets << " non-positive, " << v.undecided_tets
                             << " undecided (first " << v.first_bad_tet << ")";
  EXPECT_TRUE(v.boundary_ok()) << v.boundary_faces_missing << " missing, " << v.boundary_faces_extra
                               << " extra, " << v.boundary_self_intersections
                               << " self-intersections";
  EXPECT_EQ(v.unmapped_vertices, 0);
  EXPECT_EQ(v.flipped_input_faces, 0);
  EXPECT_LE(v.max_distance_rel, 1e-2);
  EXPECT_LT(stats.coarse_faces, GetParam().max_face_ratio * input.num_faces());
  std::printf(
      "%s: %d input faces -> %d boundary faces, %d tets (%d slab), distance %.3g, "
      "min scaled J %.3g, MIPS mean %.0f max %.3g, thickened %d, curved/blended/linear "
      "%d/%d/%d, shell section %s\n",
      GetParam().file, input.num_faces(), stats.coarse_faces, v.tets, stats.slab_tets,
      v.max_distance_rel, v.min_scaled_jacobian, v.mean_mips, v.max_mips, stats.thickened_vertices,
      stats.faces_fully_curved, stats.faces_blended, stats.faces_linear,
      stats.shell_section_verified ? "verified" : "NOT verified");
}

INSTANTIATE_TEST_SUITE_P(SmallDevMeshes, CurvedData,
                         // knight_decimated is already coarse (1000 faces): ε = 1% leaves
                         // little to remove under a bound on the linear middle surface.
                         ::testing::Values(DataCase{"knight_decimated.obj", 0.9},
                                           DataCase{"spot.obj", 0.2}, DataCase{"bunny.obj", 0.25}));

// The curved-aware coarsening's retry path on a real mesh: spot's first attempt leaves a face in
// a thin part that cannot be fully curved (measured: 1 miss, 40 input vertices kept under the
// linear bound). The second attempt repairs that coarse shell instead of coarsening the input
// again: with only the missed face's vertices strict no split there passes the prism positivity
// test (the pillars of the thin part are short), with the two edge steps around it strict the
// splits go through (measured: 11 splits, 356 faces, against 358 coarsened again). The validator,
// the repair path and the comparisons with re-coarsening and with the linear bound are asserted.
TEST(CurvedData, CurvedAwareCoarseningRetriesAfterAMissAndMeetsEps) {
  auto run = dev_mesh("spot.obj");
  if (!run) GTEST_SKIP() << k_no_data;
  const curvefem::SurfaceMesh& input = run->input;
  cv::CurvedMeshOptions& o = run->options;
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh m = cv::build_curved_mesh(input, o, stats);
  const cv::CurvedValidation v = cv::validate_curved_mesh(m.mesh, m.map, input);
  EXPECT_EQ(stats.curved_repairs, 1);
  EXPECT_EQ(stats.repair_failures, 0);
  EXPECT_GT(stats.repair_splits, 0);
  auto has_stage = [](const cv::CurvedMeshStats& s, const std::string& name) {
    return std::any_of(s.stage_seconds.begin(), s.stage_seconds.end(),
                       [&](const auto& e) { return e.first == name; });
  };
  EXPECT_TRUE(has_stage(stats, "repair"));
  EXPECT_FALSE(has_stage(stats, "coarsen")) << "the kept attempt did not coarsen the input";
  o.curved_repair = false;
  cv::CurvedMeshStats again;
  const cv::CurvedMesh r = cv::build_curved_mesh(input, o, again);
  EXPECT_TRUE(cv::validate_curved_mesh(r.mesh, r.map, input).valid(1e-2));
  EXPECT_EQ(again.curved_repairs, 0);
  EXPECT_TRUE(has_stage(again, "coarsen"));
  std::printf("spot: repaired %d faces (%d splits), coarsened again %d faces\n", stats.coarse_faces,
              stats.repair_splits, again.coarse_faces);
  EXPECT_LE(stats.coarse_faces, 1.05 * again.coarse_faces);
  o.curved_repair = true;
  o.curved_coarsening = false;
  cv::CurvedMeshStats linear;
  cv::build_curved_mesh(input, o, linear);
  std::printf("spot: curved-aware attempt %d, %d strict vertices, %d faces (linear bound %d)\n",
              stats.curved_attempts, stats.strict_vertices, stats.coarse_faces,
              linear.coarse_faces);
  EXPECT_TRUE(v.valid(1e-2));
  EXPECT_LE(v.max_distance_rel, 1e-2);
  EXPECT_TRUE(stats.curved_coarsening);
  EXPECT_GE(stats.curved_attempts, 2) << "the retry path is what this test is about";
  EXPECT_GT(stats.strict_vertices, 0);
  // The shell is built once (its own stage), then the first attempt is discarded.
  ASSERT_GE(stats.stage_seconds.size(), 2u);
  EXPECT_EQ(stats.stage_seconds[0].first, "shell");
  EXPECT_EQ(stats.stage_seconds[1].first, "discarded attempt 1");
  EXPECT_LT(stats.coarse_faces, 0.8 * linear.coarse_faces);
}

// The widening step of the retry on a real mesh: bunny's misses move between attempts (measured:
// 3, then 14 faces), so from the third attempt on the linear bound also holds around every needed
// face whose slab the thickening pulled above the shell's base (attempt 3: 3 misses, attempt 4:
// none, 640 faces); before the widening, bunny fell back to the linear bound everywhere (856).
// With two phases (attempts 2-4 resume from the linear-bound shell): attempt 4, 704 faces.
TEST(CurvedData, CurvedAwareCoarseningWidensAroundPulledSlabsOnBunny) {
  auto run = dev_mesh("bunny.obj");
  if (!run) GTEST_SKIP() << k_no_data;
  const curvefem::SurfaceMesh& input = run->input;
  cv::CurvedMeshOptions& o = run->options;
  // The bunny unrefined: its two long filled-hole faces, bisected by the shape refinement (on by
  // default since 2026-12-04), no longer send the coarsening through a widened attempt (attempt
  // 2, 704 faces), and the widening is what this test is about.
  o.shape_refine = 0;
  // The shells these numbers come from: the bare section condition. With the distortion bound
  // (the default since 2026-12-06) the coarse shell differs and this test's premise no longer
  // holds on bunny.
  o.shell_pillar_cos = 0;
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh m = cv::build_curved_mesh(input, o, stats);
  const cv::CurvedValidation v = cv::validate_curved_mesh(m.mesh, m.map, input);
  o.curved_coarsening = false;
  cv::CurvedMeshStats linear;
  cv::build_curved_mesh(input, o, linear);
  std::printf(
      "bunny: curved-aware attempt %d (widened %d), %d strict vertices, %d faces (linear "
      "bound %d)\n",
      stats.curved_attempts, int(stats.curved_widened), stats.strict_vertices, stats.coarse_faces,
      linear.coarse_faces);
  EXPECT_TRUE(v.valid(1e-2));
  EXPECT_LE(v.max_distance_rel, 1e-2);
  EXPECT_TRUE(stats.curved_coarsening) << "the kept attempt uses the curved-aware bound";
  EXPECT_TRUE(stats.curved_widened);
  EXPECT_GE(stats.curved_attempts, 3);
  EXPECT_LT(stats.coarse_faces, 0.85 * linear.coarse_faces);
  // The attempts after the first resumed from one linear-bound coarsening (two phases): that
  // shell is the linear mesh's coarse shell.
  EXPECT_EQ(stats.linear_phase_faces, linear.coarse_faces);
}

// --exterior on real meshes: the shell's own tops self-intersect between coarse faces (spot,
// bunny, elephant, knight_decimated), which Gmsh's boundary recovery refused ("segment-facet
// intersection") before the outer surface was repaired like the inner one. Measured on spot at
// K = 3: valid, 398 boundary faces in one attempt (the coarsening also certifies the outer slab
// of every face it lets beyond ε of its linear triangle).
TEST(CurvedData, ExteriorOnSpotRepairsTheOuterSurfaceAndIsValid) {
  auto run = dev_mesh("spot.obj");
  if (!run) GTEST_SKIP() << k_no_data;
  const curvefem::SurfaceMesh& input = run->input;
  cv::CurvedMeshOptions& o = run->options;
  o.exterior = true;
  // The shell the crossing tops come from: the bare section condition (with the distortion
  // bound, the default since 2026-12-06, spot's tops no longer cross: 0 lowered).
  o.shell_pillar_cos = 0;
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh m = cv::build_curved_mesh(input, o, stats);
  const cv::CurvedValidation v = cv::validate_curved_mesh(m.mesh, m.map, input);
  std::printf(
      "spot exterior: %d faces, attempt %d, outer %d raised / %d lowered, min sJ outer "
      "slab %g\n",
      stats.coarse_faces, stats.curved_attempts, stats.outer_raised_vertices,
      stats.outer_lowered_vertices, v.quality_by_tag.at(3).min_scaled_jacobian);
  EXPECT_TRUE(v.valid(1e-2));
  EXPECT_TRUE(v.exterior);
  EXPECT_EQ(v.exterior_faces_off_box, 0);
  EXPECT_GT(stats.outer_lowered_vertices, 0) << "spot's shell tops cross: the repair is the point";
  EXPECT_GT(stats.exterior_tets, 0);
}

// The distortion repair lowers a folded patch together with the neighbours whose slabs its
// straightened edges uncertify. Before those neighbours could join, fertility at K = 4 kept a
// folded patch that the repair could have lowered, and its slab tet had a sampled scaled Jacobian
// of 1.2e-3 (curvefem mesh, one thread; 2.0e-2 with the join). Left below the floor: only
// patches that need full curving for ε (the coarsening's side, not the repair's).
TEST(CurvedData, DistortionRepairLowersTheNeighboursAFoldedPatchUncertifies) {
  auto run = dev_mesh("fertility.obj");
  if (!run) GTEST_SKIP() << k_no_data;
  cv::CurvedMeshOptions& o = run->options;
  o.order = 4;
  // The shell the folded patch comes from: the bare section condition. With the distortion
  // bound (the default since 2026-12-06) the coarse shell differs and this test's premise no
  // longer holds on fertility.
  o.shell_pillar_cos = 0;
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh m = cv::build_curved_mesh(run->input, o, stats);
  const cv::CurvedValidation v = cv::validate_curved_mesh(m.mesh, m.map, run->input);
  std::printf(
      "fertility K = 4: below the floor %d -> %d (%d need full curving), folded %d -> %d, "
      "lowered %d; min sJ %g, max MIPS %g\n",
      stats.distorted_faces_before, stats.distorted_faces_after, stats.distorted_needed_after,
      stats.folded_faces_before, stats.folded_faces_after, stats.faces_lowered_for_distortion,
      v.min_scaled_jacobian, v.max_mips);
  EXPECT_TRUE(v.valid(1e-2));
  EXPECT_GT(stats.folded_faces_before, 0);
  EXPECT_EQ(stats.distorted_faces_after, stats.distorted_needed_after);
  EXPECT_GE(v.min_scaled_jacobian, 1e-2);
  EXPECT_LT(v.max_mips, 1e4);
}
