// Shell simplification keeps every shell invariant (integration label: ~1 s per thread count).

#include <gtest/gtest.h>

#include "meshing/core/primitives.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {
sh::Shell build(const SurfaceMesh& s, sh::ShellStats& stats) {
  sh::ShellOptions o;
  return sh::build_shell(s, o, stats);
}
}  // namespace

TEST(ShellSimplify, CoarsensASphereShellAndKeepsItValid) {
  const SurfaceMesh sphere = curvefem::make_icosphere(3);  // 1280 faces
  sh::ShellStats stats;
  const sh::Shell shell = build(sphere, stats);
  for (int threads : {1, 2}) {
    sh::SimplifyOptions o;
    o.threads = threads;
    sh::SimplifyStats s;
    const sh::Shell coarse = sh::simplify_shell(shell, sphere, o, s);
    EXPECT_EQ(s.faces_before, 1280);
    EXPECT_EQ(s.faces_after, coarse.F.rows());
    EXPECT_LT(coarse.F.rows(), 1280 / 3) << threads << " threads";
    const sh::ShellVerification v = sh::verify_shell(coarse, sphere);
    EXPECT_TRUE(v.positive()) << threads;
    EXPECT_TRUE(v.separated()) << threads;
    EXPECT_TRUE(v.section()) << threads;
    EXPECT_EQ(v.roundtrip_failures, 0) << threads;
    EXPECT_LT(v.roundtrip_max_error_rel, 1e-12) << threads;
    // Middle vertices are input vertices (half-edge collapses keep positions).
    for (int m = 0; m < coarse.mid.rows(); ++m) {
      ASSERT_GE(coarse.input_vertex[m], 0);
      EXPECT_EQ((coarse.mid.row(m) - sphere.V.row(coarse.input_vertex[m])).norm(), 0.0);
    }
  }
}

TEST(ShellSimplify, CoarsensABoxShellAcrossSharpEdges) {
  // With section contact (not closed touching) the faces across the box's 90° edges no longer
  // block every collapse near an edge: the flat sides coarsen and the result stays a section.
  const SurfaceMesh box = curvefem::make_box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 1), 6);
  sh::ShellStats stats;
  const sh::Shell shell = build(box, stats);
  sh::SimplifyOptions o;
  sh::SimplifyStats s;
  const sh::Shell coarse = sh::simplify_shell(shell, box, o, s);
  EXPECT_LT(s.faces_after, s.faces_before / 2);
  const sh::ShellVerification v = sh::verify_shell(coarse, box);
  EXPECT_TRUE(v.positive());
  EXPECT_TRUE(v.separated());
  EXPECT_TRUE(v.section()) << v.non_section_faces;
  EXPECT_EQ(v.roundtrip_failures, 0);
}
