// Geometric textures (thesis §4.4, Fig. 4.27): the tile split at the reference prism's tets has
// every piece inside one tet, the shell maps each piece affinely (the mapped centroid is the
// centroid of the mapped corners), and the copies do not intersect (exact check).

#include <gtest/gtest.h>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/adversarial.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/prism_split.hpp"
#include "meshing/shell/geometric_texture.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"
#include "tests/meshing/shell/coarse_shell.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

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
