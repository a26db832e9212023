// Real meshes (data label): the shell of small dev meshes is positive, separated from the input,
// and maps every input vertex back to itself through P⁻¹ and P (before and after
// simplification), and is a section of it (exact section-contact test; test_shell_data_all, label
// slow, checks all 19 dev meshes).

#include <gtest/gtest.h>

#include "meshing/core/error.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"
#include "tests/support/test_support.hpp"

namespace sh = curvefem::meshing::shell;

class ShellData : public ::testing::TestWithParam<const char*> {};

TEST_P(ShellData, ValidShellAndExactRoundtrip) {
  const auto dir = curvefem::test::shared_data_dir();
  if (!dir) GTEST_SKIP() << "../shared/data not found: real-mesh shell test skipped";
  const curvefem::SurfaceMesh input = curvefem::io::read_surface(*dir / "dev" / GetParam());
  sh::ShellStats stats;
  const sh::Shell shell = sh::build_shell(input, sh::ShellOptions{}, stats);
  const sh::ShellVerification v = sh::verify_shell(shell, input);
  EXPECT_TRUE(v.positive()) << v.non_positive_faces;
  EXPECT_TRUE(v.separated()) << v.intersecting_input_faces;
  EXPECT_EQ(v.roundtrip_failures, 0);
  EXPECT_LE(v.roundtrip_max_error_rel, 1e-9);
  // Section contact (not closed touching) decides which faces the pillar test applies to: the
  // real meshes' shells are sections (shell_intersection.cpp, benchmarks/results/shell_section.md).
  EXPECT_TRUE(v.section()) << v.non_section_faces;
  std::printf("%s: %d prisms, section fails on %d\n", GetParam(), v.faces, v.non_section_faces);

  sh::SimplifyOptions o;
  o.threads = 2;
  sh::SimplifyStats s;
  const sh::Shell coarse = sh::simplify_shell(shell, input, o, s);
  const sh::ShellVerification w = sh::verify_shell(coarse, input);
  EXPECT_LT(s.faces_after, s.faces_before / 2);
  EXPECT_TRUE(w.positive());
  EXPECT_TRUE(w.separated());
  EXPECT_EQ(w.roundtrip_failures, 0);
  EXPECT_LE(w.roundtrip_max_error_rel, 1e-9);
  // Simplification never adds section violations: only prisms that already failed can remain.
  EXPECT_LE(w.non_section_faces, v.non_section_faces);
  EXPECT_TRUE(w.section()) << w.non_section_faces;
  std::printf("%s: simplified to %d prisms (%.1f%%), section fails on %d\n", GetParam(), w.faces,
              100.0 * w.faces / input.num_faces(), w.non_section_faces);
}

INSTANTIATE_TEST_SUITE_P(Shell, ShellData, ::testing::Values("spot.obj", "bunny.obj"),
                         [](const auto& info) {
                           const std::string name(info.param);
                           return name.substr(0, name.find('.'));
                         });

// A real self-intersecting mesh of ../shared/data/bad (the CGAL camel, 19,536 faces, 20 pairs; the
// ABC part of three overlapping components there takes 20 s: benchmarks/run_local_shell.py): no
// embedded shell exists, and the locally injective one (local_sheets.hpp) is built, coarsened and
// verified.
class ShellDataSelfIntersecting : public ::testing::TestWithParam<const char*> {};

TEST_P(ShellDataSelfIntersecting, LocallyInjectiveShellIsVerified) {
  const auto dir = curvefem::test::shared_data_dir();
  if (!dir) GTEST_SKIP() << "../shared/data not found: self-intersecting real-mesh test skipped";
  const curvefem::SurfaceMesh input = curvefem::io::read_surface(*dir / "bad" / GetParam());
  sh::ShellStats stats;
  EXPECT_THROW(sh::build_shell(input, sh::ShellOptions{}, stats), curvefem::MeshingError);
  sh::ShellOptions local;
  local.local_sheets = true;
  const sh::Shell shell = sh::build_shell(input, local, stats);
  sh::SimplifyOptions o;
  o.threads = 2;
  o.zoom = 0.1 * curvefem::bbox_longest_edge(input.V);
  sh::SimplifyStats s;
  const sh::Shell coarse = sh::simplify_shell(shell, input, o, s);
  EXPECT_LT(s.faces_after, s.faces_before);
  const sh::ShellVerification w = sh::verify_shell(coarse, input);
  EXPECT_TRUE(w.positive());
  EXPECT_TRUE(w.separated()) << w.intersecting_input_faces;
  EXPECT_TRUE(w.section()) << w.non_section_faces;
  EXPECT_EQ(w.roundtrip_failures, 0);
  EXPECT_LE(w.roundtrip_max_error_rel, 1e-12);
  std::printf("%s: %d -> %d prisms\n", GetParam(), s.faces_before, s.faces_after);
}

INSTANTIATE_TEST_SUITE_P(Bad, ShellDataSelfIntersecting,
                         ::testing::Values("selfintersect_camel.off"));
