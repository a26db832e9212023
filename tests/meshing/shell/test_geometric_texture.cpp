// Geometric textures (thesis §4.4, Fig. 4.27): the tile split at the reference prism's tets has
// every piece inside one tet, the shell maps each piece affinely (the mapped centroid is the
// centroid of the mapped corners), and the copies do not intersect (exact check).

#include <gtest/gtest.h>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/adversarial.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/prism_split.hpp"
#include "meshing/shell/geometric_texture.hpp"
#include "meshing/shell/nested_cages.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"
#include "tests/meshing/shell/coarse_shell.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {

// A triangular slab over most of the reference triangle, from t0 to t1.
SurfaceMesh slab_tile(double t0, double t1) {
  SurfaceMesh tile;
  tile.V.resize(6, 3);
  tile.V << 0.05, 0.05, t0, 0.9, 0.05, t0, 0.05, 0.9, t0,  //
      0.05, 0.05, t1, 0.9, 0.05, t1, 0.05, 0.9, t1;
  tile.F.resize(8, 3);
  tile.F << 0, 2, 1, 3, 4, 5, 0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 2, 0, 3, 2, 3, 5;
  sh::check_tile(tile, "slab");
  return tile;
}

// Exactly self-intersecting pairs of a surface expected free of degenerate faces.
std::size_t pairs(const SurfaceMesh& m) {
  const auto degenerate = curvefem::check::exactly_degenerate_faces(m.V, m.F);
  EXPECT_EQ(std::count(degenerate.begin(), degenerate.end(), 1), 0);
  return curvefem::check::find_self_intersections(m.V, m.F, degenerate, false).pairs.size();
}

}  // namespace

TEST(GeometricTexture, SplitPiecesLieInOneTetOfTheReferencePrism) {
  for (const auto& name : sh::builtin_tile_names())
    for (bool type_a : {false, true}) {
      const SurfaceMesh tile = sh::builtin_tile(name);
      const SurfaceMesh split = sh::split_tile_at_tets(tile, type_a);
      EXPECT_GT(split.num_faces(), tile.num_faces()) << name;
      // The planes (c, d) of split_tile_at_tets, in (a, b, t).
      const Eigen::Vector3d single = type_a ? Eigen::Vector3d(-1, 0, 2) : Eigen::Vector3d(0, -1, 2);
      const std::pair<Eigen::Vector3d, double> planes[5] = {
          {{0, 0, 2}, -1}, {single, 0}, {single, -1}, {{-1, -1, 2}, 0}, {{-1, -1, 2}, -1}};
      for (int f = 0; f < split.num_faces(); ++f)
        for (const auto& [c, d] : planes) {
          double lo = 0, hi = 0;
          for (int k = 0; k < 3; ++k) {
            const double g = c.dot(Eigen::Vector3d(split.V.row(split.F(f, k)))) + d;
            lo = std::min(lo, g);
            hi = std::max(hi, g);
          }
          ASSERT_FALSE(lo < -1e-12 && hi > 1e-12) << name << " face " << f;
        }
      // Same surface: the area is kept.
      auto area = [](const SurfaceMesh& m) {
        double s = 0;
        for (int f = 0; f < m.num_faces(); ++f) {
          const Eigen::Vector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)),
                                c = m.V.row(m.F(f, 2));
          s += 0.5 * (b - a).cross(c - a).norm();
        }
        return s;
      };
      EXPECT_NEAR(area(split), area(tile), 1e-12 * area(tile)) << name;
    }
}

TEST(GeometricTexture, CopiesAreTheExactImageAndDoNotIntersect) {
  const SurfaceMesh input = curvefem::make_adversarial("noise_sphere_5");
  const sh::Shell shell = curvefem::test::coarse_shell(input);
  ASSERT_TRUE(sh::verify_shell(shell, input).valid());
  const sh::ShellProjection projection(shell, input);
  const SurfaceMesh tile = sh::builtin_tile("knob");
  const sh::TexturedSurface t = sh::apply_geometric_texture(projection, tile);
  const SurfaceMesh split[2] = {sh::split_tile_at_tets(tile, false),
                                sh::split_tile_at_tets(tile, true)};
  // Affine on every piece: the image of a piece's centroid is the centroid of its mapped corners.
  const double unit = curvefem::bbox_longest_edge(input.V);
  double worst = 0;
  int face = 0;
  for (int f = 0; f < shell.F.rows(); ++f) {
    const SurfaceMesh& piece = split[curvefem::is_type_a(Eigen::Vector3i(shell.F.row(f))) ? 1 : 0];
    for (int k = 0; k < piece.num_faces(); ++k, ++face) {
      ASSERT_EQ(t.mesh.tags[face], f);
      Eigen::Vector3d c = Eigen::Vector3d::Zero(), mapped = Eigen::Vector3d::Zero();
      for (int j = 0; j < 3; ++j) {
        c += piece.V.row(piece.F(k, j)).transpose() / 3;
        mapped += t.mesh.V.row(t.mesh.F(face, j)).transpose() / 3;
      }
      sh::PrismPoint q;
      q.face = f;
      q.u = c.x();
      q.v = c.y();
      q.h = 2 * c.z() - 1;
      worst = std::max(worst, (projection.point(q) - mapped).norm());
    }
  }
  EXPECT_LT(worst, 1e-12 * unit);
  const auto degenerate = curvefem::check::exactly_degenerate_faces(t.mesh.V, t.mesh.F);
  EXPECT_EQ(std::count(degenerate.begin(), degenerate.end(), 1), 0);
  EXPECT_EQ(
      curvefem::check::find_self_intersections(t.mesh.V, t.mesh.F, degenerate, false).pairs.size(),
      0u);
}

TEST(GeometricTexture, TopSurfaceSelfIntersectionsAreShortenedAwaySoCopiesDoNotMeet) {
  // A split ring with a slit of 0.1 ε: the simplified shell's top surfaces meet across the slit,
  // so the upper halves of prisms on either side overlap and a tile filling most of the upper
  // half meets the copies across. Shortening those top pillars (separate_shell_side, as for
  // nested cages; separate_for_tile) removes the overlap.
  const SurfaceMesh input = curvefem::make_adversarial("split_ring_01");
  sh::Shell shell = curvefem::test::coarse_shell(input);
  const SurfaceMesh tile = slab_tile(0.9, 0.97);
  {
    const sh::ShellProjection projection(shell, input);
    EXPECT_GT(pairs(sh::apply_geometric_texture(projection, tile).mesh), 0u);
  }
  const sh::TileSeparation sep = sh::separate_for_tile(shell, input, tile);
  EXPECT_TRUE(sep.top);
  EXPECT_FALSE(sep.base);  // the tile stays in the upper half
  EXPECT_EQ(sep.top_failure, "");
  const sh::SeparationStats& stats = sep.top_stats;
  EXPECT_GT(stats.pairs_before, 0);
  EXPECT_GT(stats.rounds, 0);
  EXPECT_GT(stats.shortened_pillars, 0);
  EXPECT_TRUE(sh::verify_shell(shell, input).valid());
  SurfaceMesh top;
  top.V = shell.top;
  top.F = shell.F;
  EXPECT_EQ(pairs(top), 0u);
  const sh::ShellProjection projection(shell, input);
  EXPECT_EQ(pairs(sh::apply_geometric_texture(projection, tile).mesh), 0u);
}

TEST(GeometricTexture, ATileInTheLowerHalfSeparatesTheBaseSurface) {
  // A slab at t in [0.03, 0.1] on a noisy sphere, whose simplified shell's base surface meets
  // itself (17 pairs measured, removed in one round): only the base surface is separated (the
  // top is left alone), and the copies below the middle surface do not meet.
  const SurfaceMesh input = curvefem::make_adversarial("noise_sphere_5");
  sh::Shell shell = curvefem::test::coarse_shell(input);
  const SurfaceMesh tile = slab_tile(0.03, 0.1);
  const Eigen::MatrixXd top_before = shell.top;
  const sh::TileSeparation sep = sh::separate_for_tile(shell, input, tile);
  EXPECT_FALSE(sep.top);
  EXPECT_TRUE(sep.base);
  EXPECT_EQ(sep.base_failure, "");
  EXPECT_GT(sep.base_stats.pairs_before, 0);
  EXPECT_GT(sep.base_stats.rounds, 0);
  EXPECT_EQ(shell.top, top_before);  // the top is left alone
  EXPECT_TRUE(sh::verify_shell(shell, input).valid());
  SurfaceMesh base;
  base.V = shell.base;
  base.F = shell.F;
  EXPECT_EQ(pairs(base), 0u);
  const sh::ShellProjection projection(shell, input);
  EXPECT_EQ(pairs(sh::apply_geometric_texture(projection, tile).mesh), 0u);
}

TEST(GeometricTexture, PinchedPrismsGetNoCopyAndTheOthersDoNotMeet) {
  // needle_sphere_8: the shell has zero thickness at the 8 needle tips, and the prisms there
  // have flat tets, which would flatten the tile's pieces in them (`curvefem shell --texture
  // knob` gave 180 degenerate faces and 1,636 meeting pairs before they were left out).
  const SurfaceMesh input = curvefem::make_adversarial("needle_sphere_8");
  const sh::Shell shell = curvefem::test::coarse_shell(input);
  ASSERT_TRUE(sh::verify_shell(shell, input).valid());
  int pinched = 0;
  std::vector<char> at_tip(std::size_t(shell.F.rows()), 0);
  for (int f = 0; f < shell.F.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      if (shell.singular[std::size_t(shell.F(f, c))]) at_tip[std::size_t(f)] = 1;
  for (char c : at_tip) pinched += c;
  EXPECT_EQ(std::count(shell.singular.begin(), shell.singular.end(), 1), 8);
  ASSERT_GT(pinched, 0);
  const sh::ShellProjection projection(shell, input);
  const sh::TexturedSurface t = sh::apply_geometric_texture(projection, sh::builtin_tile("knob"));
  EXPECT_EQ(t.skipped_pinched, pinched);
  std::vector<char> copied(std::size_t(shell.F.rows()), 0);
  for (int tag : t.mesh.tags) copied[std::size_t(tag)] = 1;
  for (int f = 0; f < shell.F.rows(); ++f)
    EXPECT_NE(copied[std::size_t(f)], at_tip[std::size_t(f)]) << f;  // a copy iff not pinched
  EXPECT_EQ(pairs(t.mesh), 0u);
}

TEST(GeometricTexture, ATileOutsideTheUnitPrismOrUnknownIsRefused) {
  SurfaceMesh tile = sh::builtin_tile("spike");
  tile.V(3, 2) = 1.5;
  try {
    sh::check_tile(tile, "tile.obj");
    ADD_FAILURE();
  } catch (const curvefem::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tile.obj: tile vertex 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(sh::builtin_tile("chainmail"), curvefem::InputError);
}
