// Real meshes (data label): the inside of small dev meshes is filled with the surface kept
// exactly (verify_tetfill valid, vertices bit-identical, every input triangle a boundary face).

#include <gtest/gtest.h>

#include <cstdio>

#include "meshing/io/surface_io.hpp"
#include "meshing/tetfill/tetfill.hpp"
#include "tests/support/test_support.hpp"

namespace tf = curvefem::meshing::tetfill;

class TetFillData : public ::testing::TestWithParam<const char*> {};

TEST_P(TetFillData, BoundaryKeptExactly) {
  const auto dir = curvefem::test::shared_data_dir();
  if (!dir) GTEST_SKIP() << curvefem::test::k_no_data_message;
  const curvefem::SurfaceMesh input = curvefem::io::read_surface(*dir / "dev" / GetParam());
  const tf::TetFillResult r = tf::fill_interior(input.V, input.F);
  const tf::TetFillVerification v = tf::verify_tetfill(input.V, input.F, r);
  EXPECT_TRUE(v.valid());
  EXPECT_EQ(v.non_positive_tets, 0);
  EXPECT_EQ(v.missing_boundary_faces, 0);
  EXPECT_EQ(v.extra_boundary_faces, 0);
  EXPECT_EQ(v.bad_interior_faces, 0);
  EXPECT_EQ(v.moved_boundary_vertices, 0);
  EXPECT_LE(v.volume_error_rel, 1e-12);
  EXPECT_EQ(r.boundary_vertices, input.num_vertices());
  EXPECT_TRUE((r.V.topRows(input.num_vertices()).array() == input.V.array()).all());
  // At least one tet per two boundary faces, and not absurdly many.
  EXPECT_GE(r.T.rows(), input.num_faces() / 2);
  EXPECT_LE(r.T.rows(), 20 * input.num_faces());
  std::printf("%s: %d faces -> %lld tets, %lld interior vertices, %.2f s\n", GetParam(),
              input.num_faces(), static_cast<long long>(r.T.rows()),
              static_cast<long long>(r.V.rows() - input.num_vertices()), r.seconds);
}

INSTANTIATE_TEST_SUITE_P(TetFill, TetFillData,
                         ::testing::Values("spot.obj", "bunny.obj", "fandisk.obj"),
                         [](const auto& info) {
                           const std::string name(info.param);
                           return name.substr(0, name.find('.'));
                         });
