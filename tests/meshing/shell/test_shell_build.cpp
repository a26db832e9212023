// Shell construction, projection and verification on shapes built in code; the data test builds
// a shell on every mesh of ../shared/data/dev.

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/shell/projection.hpp"
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

TEST(ShellBuild, SphereShellIsValidAndItsProjectionIsExact) {
  const SurfaceMesh sphere = curvefem::make_icosphere(3);
  sh::ShellStats stats;
  const sh::Shell shell = build(sphere, stats);
  EXPECT_EQ(shell.F.rows(), sphere.F.rows());
  EXPECT_EQ(stats.singular_vertices, 0);
  // The cap (2% of the bbox edge 2) binds everywhere on a convex sphere.
  EXPECT_NEAR(stats.median_thickness_rel, 0.02, 1e-12);
  const sh::ShellVerification v = sh::verify_shell(shell, sphere);
  EXPECT_TRUE(v.positive());
  EXPECT_TRUE(v.separated());
  EXPECT_TRUE(v.section());
  EXPECT_EQ(v.roundtrip_failures, 0);
  EXPECT_LT(v.roundtrip_max_error_rel, 1e-12);
  // A point between base and top projects along its fiber onto the face it lies over.
  const sh::ShellProjection p(shell, sphere);
  const Eigen::Vector3d c = (Eigen::Vector3d(sphere.V.row(sphere.F(7, 0))) +
                             Eigen::Vector3d(sphere.V.row(sphere.F(7, 1))) +
                             Eigen::Vector3d(sphere.V.row(sphere.F(7, 2)))) /
                            3.0;
  const Eigen::Vector3d n = (Eigen::Vector3d(sphere.V.row(sphere.F(7, 1))) -
                             Eigen::Vector3d(sphere.V.row(sphere.F(7, 0))))
                                .cross(Eigen::Vector3d(sphere.V.row(sphere.F(7, 2))) -
                                       Eigen::Vector3d(sphere.V.row(sphere.F(7, 0))))
                                .normalized();
  for (double h : {-0.01, -0.001, 0.0, 0.002, 0.015}) {
    const auto q = p.locate(c + h * n);
    ASSERT_TRUE(q.has_value()) << h;
    EXPECT_EQ(q->face, 7);
    EXPECT_EQ(h < 0, q->h < 0) << h;
    const auto s = p.project(*q);
    ASSERT_TRUE(s.has_value());
    EXPECT_EQ(s->face, 7);
    // The fiber through the centroid's (u, v) meets the face at the centroid only when the
    // pillars are parallel; the point stays inside the face, near the centroid.
    EXPECT_GT(s->bary.minCoeff(), 0.2);
    // point() inverts locate().
    EXPECT_LT((p.point(*q) - (c + h * n)).norm(), 1e-12);
  }
  EXPECT_FALSE(p.is_inside(Eigen::Vector3d(0, 0, 0)));
  EXPECT_FALSE(p.is_inside(Eigen::Vector3d(2, 0, 0)));
}

TEST(ShellBuild, ThinSlabShrinksToStaySeparated) {
  // A box 1 × 1 × 0.01: rays from the large faces hit the opposite face at 0.01, so pillars there
  // are at most 0.8 × 0.01 long on each side, and the shell stays separated from the input.
  const SurfaceMesh slab =
      curvefem::make_box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 0.01), 4);
  sh::ShellStats stats;
  const sh::Shell shell = build(slab, stats);
  EXPECT_LE(stats.median_thickness_rel, 0.8 * 0.01 + 1e-12);
  const sh::ShellVerification v = sh::verify_shell(shell, slab);
  EXPECT_TRUE(v.positive());
  EXPECT_TRUE(v.separated());
  EXPECT_EQ(v.roundtrip_failures, 0);
  EXPECT_LT(v.roundtrip_max_error_rel, 1e-12);
}

TEST(ShellBuild, RejectsOpenAndMisorientedInput) {
  SurfaceMesh open = curvefem::make_icosphere(1);
  open.F.conservativeResize(open.F.rows() - 1, 3);
  sh::ShellStats stats;
  EXPECT_THROW(build(open, stats), curvefem::InputError);
  SurfaceMesh flipped = curvefem::make_icosphere(1);
  std::swap(flipped.F(0, 1), flipped.F(0, 2));
  EXPECT_THROW(build(flipped, stats), curvefem::InputError);
}

TEST(ShellBuild, BoxShellIsASectionAtSharpEdges) {
  // At a 90° edge the face across the edge touches the prism only along the shared edge, on the
  // lateral boundary: not section contact, so the box's shell is a section (the closed
  // "touching" test flagged almost every prism here).
  const SurfaceMesh box = curvefem::make_box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 1), 4);
  sh::ShellStats stats;
  const sh::Shell shell = build(box, stats);
  const sh::ShellVerification v = sh::verify_shell(shell, box);
  EXPECT_TRUE(v.positive());
  EXPECT_TRUE(v.separated());
  EXPECT_TRUE(v.section()) << v.non_section_faces << " of " << v.faces;
  EXPECT_EQ(v.roundtrip_failures, 0);
}

TEST(ShellBuild, VerifyFlagsAReversedPillar) {
  // Swapping base and top of one vertex reverses its pillar: the faces around it lie in the mid
  // triangles of their prisms (coplanar section contact) with a negative dot product.
  const SurfaceMesh sphere = curvefem::make_icosphere(2);
  sh::ShellStats stats;
  sh::Shell shell = build(sphere, stats);
  const Eigen::RowVector3d b = shell.base.row(0);
  shell.base.row(0) = shell.top.row(0);
  shell.top.row(0) = b;
  const sh::ShellVerification v = sh::verify_shell(shell, sphere);
  EXPECT_FALSE(v.positive());
  EXPECT_GE(v.non_section_faces, 5);  // the 5 or 6 faces around vertex 0, and maybe neighbours
}
