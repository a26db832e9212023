#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <numbers>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/primitives.hpp"
#include "tests/support/test_support.hpp"

using namespace curvefem;

TEST(Error, MessageNamesFileLineAndIds) {
  const InputError e("index 7 out of range", {.file = "a.obj", .line = 12, .face = 3});
  EXPECT_STREQ(e.what(), "a.obj:12: index 7 out of range (face 3)");
  EXPECT_EQ(e.exit_code(), 2);
  const InputError b("truncated", {.file = "b.stl", .byte_offset = 84});
  EXPECT_STREQ(b.what(), "b.stl: byte 84: truncated");
  EXPECT_EQ(IoError("x").exit_code(), 4);
}

TEST(Error, VerifyThrowsWithLocation) {
  try {
    CF_VERIFY(1 + 1 == 3, "arithmetic");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("arithmetic"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("test_core_misc.cpp"), std::string::npos);
  }
}

TEST(AtomicFile, NoPartialOutputOnFailure) {
  const auto dir = test::scratch_dir("atomic");
  const auto target = dir / "out.txt";
  { std::ofstream(target) << "old"; }
  try {
    AtomicFile f(target);
    std::ofstream(f.temp_path()) << "half-written";
    throw std::runtime_error("writer failed");
  } catch (const std::runtime_error&) {
  }
  std::ifstream in(target);
  std::string s;
  in >> s;
  EXPECT_EQ(s, "old");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 1);  // no temp left
  write_text_file_atomic(target, "new");
  std::ifstream in2(target);
  in2 >> s;
  EXPECT_EQ(s, "new");
}

TEST(StagedOutputDir, AFailedRunLeavesNoNewFileAndNoFolderItCreated) {
  const auto dir = test::scratch_dir("staged");
  {  // a folder it creates and never commits: removed
    StagedOutputDir out(dir / "new");
    std::ofstream(out.path("a.txt")) << "x";
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "new"));
  std::filesystem::create_directories(dir / "old");
  {  // a folder that was there: kept, with nothing new in it
    StagedOutputDir out(dir / "old");
    std::ofstream(out.path("a.txt")) << "x";
  }
  EXPECT_TRUE(std::filesystem::is_directory(dir / "old"));
  EXPECT_TRUE(std::filesystem::is_empty(dir / "old"));
  {  // committed: the files are there
    StagedOutputDir out(dir / "done");
    std::ofstream(out.path("a.txt")) << "x";
    out.commit();
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "done" / "a.txt"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir / "done"), {}), 1);
}

TEST(Primitives, ClosedOutwardWithExpectedVolume) {
  const auto sphere = make_icosphere(4);
  EXPECT_EQ(sphere.num_faces(), 20 * 256);
  EXPECT_EQ(sphere.num_vertices() - 3 * sphere.num_faces() / 2 + sphere.num_faces(), 2);  // χ
  EXPECT_NEAR(signed_volume(sphere), 4.0 / 3.0 * std::numbers::pi, 0.01);
  const auto box = make_box({0, 0, 0}, {1, 2, 3}, 3);
  EXPECT_EQ(box.num_faces(), 12 * 9);
  EXPECT_NEAR(signed_volume(box), 6.0, 1e-12);
  // The corners are lo and hi exactly, also where lo + (hi − lo) rounds away from hi (these two
  // were a knight_decimated exterior box before that was fixed).
  const Eigen::Vector3d lo = Eigen::Vector3d::Constant(-0.835910610281003);
  const Eigen::Vector3d hi = Eigen::Vector3d::Constant(2.6185843423430817);
  ASSERT_NE(lo[0] + (hi[0] - lo[0]), hi[0]);
  const auto odd = make_box(lo, hi, 4);
  EXPECT_EQ(Eigen::Vector3d(odd.V.colwise().maxCoeff()), hi);
  EXPECT_EQ(Eigen::Vector3d(odd.V.colwise().minCoeff()), lo);
  const auto torus = make_torus(2.0, 0.5, 64, 32);
  EXPECT_EQ(torus.num_vertices() - 3 * torus.num_faces() / 2 + torus.num_faces(), 0);
  // Polygonal ring: cross-section polygon area × path length of its centroid, discretized.
  const double a = 2 * std::numbers::pi / 64, b = 2 * std::numbers::pi / 32;
  const double poly_area = 32 / 2.0 * 0.25 * std::sin(b);
  EXPECT_NEAR(signed_volume(torus), poly_area * 2 * std::numbers::pi * 2.0 * std::sin(a) / a, 1e-3);
}

TEST(LagrangeMesh, ValidateNamesTheDefect) {
  LagrangeMesh m;
  m.order = 1;
  m.nodes = Eigen::MatrixXd::Identity(4, 3);
  m.cells.resize(1, 4);
  m.cells << 0, 1, 2, 7;
  try {
    validate_structure(m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("node id 7 out of range"), std::string::npos);
    EXPECT_EQ(e.context().element, 0);
  }
}
