// Every dev mesh (slow label: all 19, igea takes minutes): the unsimplified shell is positive,
// separated from the input, a section of it (exact open-interior contact test), and maps every
// input vertex back to itself through P⁻¹ and P to 1e-9 of the bounding box.

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "meshing/io/surface_io.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/verify.hpp"
#include "tests/support/test_support.hpp"

namespace sh = curvefem::meshing::shell;

TEST(ShellDataAll, EveryDevMeshGivesAVerifiedSection) {
  const auto dir = curvefem::test::shared_data_dir();
  if (!dir) GTEST_SKIP() << "../shared/data not found: all-dev-mesh shell test skipped";
  std::ifstream manifest(*dir / "dev" / "MANIFEST.tsv");
  ASSERT_TRUE(manifest) << "dev/MANIFEST.tsv missing";
  std::string line;
  std::getline(manifest, line);  // header: name, file, ...
  int meshes = 0;
  while (std::getline(manifest, line)) {
    std::istringstream row(line);
    std::string name, file;
    std::getline(row, name, '\t');
    std::getline(row, file, '\t');
    if (file.empty()) continue;
    SCOPED_TRACE(file);
    const curvefem::SurfaceMesh input = curvefem::io::read_surface(*dir / "dev" / file);
    sh::ShellStats stats;
    const sh::Shell shell = sh::build_shell(input, sh::ShellOptions{}, stats);
    const sh::ShellVerification v = sh::verify_shell(shell, input);
    EXPECT_TRUE(v.positive()) << v.non_positive_faces;
    EXPECT_TRUE(v.separated()) << v.intersecting_input_faces;
    EXPECT_TRUE(v.section()) << v.non_section_faces;
    EXPECT_EQ(v.roundtrip_failures, 0);
    EXPECT_LE(v.roundtrip_max_error_rel, 1e-9);
    std::printf("%s: %d prisms, section violations %d, roundtrip %.2g, %.1f s verification\n",
                file.c_str(), v.faces, v.non_section_faces, v.roundtrip_max_error_rel, v.seconds);
    ++meshes;
  }
  EXPECT_EQ(meshes, 19);
}
