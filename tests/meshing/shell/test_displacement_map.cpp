// Displacement maps through P (thesis §4.4, Fig. 4.26): the coarse middle surface and one height
// per sample rebuild a surface whose every vertex is on the input and on its sample's own fiber
// (exact point location, not the bake's fiber walk), whose distance to the input falls with the
// level, and which folds where the usual normal projection folds hundreds of times; the file
// roundtrips bit for bit and a malformed one is refused with its line. Distances and
// self-intersections come from meshing/check (CGAL), not from P.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "meshing/check/self_intersections.hpp"
#include "meshing/check/surface_distance.hpp"
#include "meshing/core/adversarial.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/shell/displacement_map.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"
#include "tests/meshing/shell/coarse_shell.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {

/// A sphere with smooth bumps of relative height `amplitude`.
SurfaceMesh bumpy_sphere(int level, double amplitude) {
  SurfaceMesh s = curvefem::make_icosphere(level);
  for (int v = 0; v < s.num_vertices(); ++v) {
    const Eigen::Vector3d p = s.V.row(v);
    s.V.row(v) *= 1 + amplitude * std::sin(4 * p.x()) * std::sin(4 * p.y()) * std::cos(3 * p.z());
  }
  return s;
}

}  // namespace

TEST(DisplacementMap, EveryRebuiltVertexIsOnTheInputAndOnItsFiberAndTheErrorFallsWithTheLevel) {
  const SurfaceMesh input = bumpy_sphere(4, 0.08);  // 5120 faces
  const sh::Shell shell = curvefem::test::coarse_shell(input);
  ASSERT_TRUE(sh::verify_shell(shell, input).valid());
  ASSERT_LT(shell.F.rows(), 200);  // coarse: the map carries the detail
  const sh::ShellProjection onto_input(shell, input);
  const double unit = curvefem::bbox_longest_edge(input.V);
  double hausdorff[4];
  const int levels[4] = {1, 2, 4, 8};
  for (int k = 0; k < 4; ++k) {
    const int L = levels[k];
    const sh::DisplacementMap map = sh::bake_displacement_map(onto_input, L);
    ASSERT_EQ(map.failures, 0) << L;
    ASSERT_EQ(int(map.h.size()), shell.F.rows() * (L + 1) * (L + 2) / 2);
    const sh::Reconstruction r = sh::reconstruct(shell, map);
    // V − E + F of the subdivision: same Euler characteristic as the coarse surface.
    EXPECT_EQ(r.mesh.num_faces(), shell.F.rows() * L * L);
    EXPECT_EQ(r.mesh.num_vertices() - r.mesh.num_faces() * 3 / 2 + r.mesh.num_faces(), 2) << L;
    const Eigen::VectorXd on = curvefem::check::distances_to_surface(r.mesh.V, input.V, input.F);
    EXPECT_LT(on.maxCoeff(), 1e-13 * unit) << L;
    const sh::FiberCheck fibers = sh::check_on_fibers(onto_input, map, r);
    EXPECT_EQ(fibers.not_located, 0) << L;
    EXPECT_LT(fibers.max_offset, 1e-12 * unit) << L;
    EXPECT_EQ(curvefem::check::count_self_intersecting_pairs(r.mesh.V, r.mesh.F), 0) << L;
    hausdorff[k] =
        curvefem::check::sampled_hausdorff(r.mesh.V, r.mesh.F, input.V, input.F).symmetric() / unit;
    RecordProperty("hausdorff_rel_L" + std::to_string(L), std::to_string(hausdorff[k]));
  }
  // Measured (50 coarse faces): 6.7e-2, 3.4e-2, 1.1e-2, 3.3e-3 of the bbox, ratios 1.96, 3.1,
  // 3.3, toward linear interpolation's 4.
  for (int k = 1; k < 4; ++k) EXPECT_GT(hausdorff[k - 1] / hausdorff[k], 1.8) << levels[k];
  EXPECT_GT(hausdorff[2] / hausdorff[3], 2.8);
  EXPECT_LT(hausdorff[3], 5e-3);
}

TEST(DisplacementMap, FoldsNowhereWhereTheNormalProjectionFolds) {
  // A noisy sphere (1280 faces, radial noise 5% of ε): displaced along the middle surface's
  // interpolated normals the level-4 surface self-intersects in hundreds of face pairs (712
  // measured) and is farther from the input; through P's fibers it does not self-intersect.
  const SurfaceMesh input = curvefem::make_adversarial("noise_sphere_5");
  const sh::Shell shell = curvefem::test::coarse_shell(input);
  ASSERT_TRUE(sh::verify_shell(shell, input).valid());
  const sh::ShellProjection onto_input(shell, input);
  const sh::DisplacementMap map = sh::bake_displacement_map(onto_input, 4);
  ASSERT_EQ(map.failures, 0);
  const sh::Reconstruction ours = sh::reconstruct(shell, map);
  double reach = 0;  // as `curvefem shell --displacement-map`: twice the longest half-pillar
  for (Eigen::Index v = 0; v < shell.mid.rows(); ++v)
    reach = std::max({reach, (shell.top.row(v) - shell.mid.row(v)).norm(),
                      (shell.base.row(v) - shell.mid.row(v)).norm()});
  int missed = -1;
  const sh::Reconstruction normals =
      sh::reconstruct_along_normals(shell, input, 4, 2 * reach, &missed);
  // The normal lines miss the input at a few points (4 of 3,842 measured), which stay on the
  // middle surface; the fibers miss nowhere.
  EXPECT_LT(missed, 20);
  const int ours_pairs = curvefem::check::count_self_intersecting_pairs(ours.mesh.V, ours.mesh.F),
            normal_pairs =
                curvefem::check::count_self_intersecting_pairs(normals.mesh.V, normals.mesh.F);
  RecordProperty("pairs_through_P", ours_pairs);
  RecordProperty("pairs_along_normals", normal_pairs);
  EXPECT_EQ(ours_pairs, 0);
  EXPECT_GT(normal_pairs, 100);
  const double h_ours =
      curvefem::check::sampled_hausdorff(ours.mesh.V, ours.mesh.F, input.V, input.F).symmetric();
  const double h_normals =
      curvefem::check::sampled_hausdorff(normals.mesh.V, normals.mesh.F, input.V, input.F)
          .symmetric();
  EXPECT_LT(h_ours, h_normals);
}

TEST(DisplacementMap, TheFileRoundtripsAndAMalformedOneIsRefusedWithItsLine) {
  const SurfaceMesh input = bumpy_sphere(3, 0.05);
  const sh::Shell shell = curvefem::test::coarse_shell(input);
  const sh::ShellProjection onto_input(shell, input);
  const sh::DisplacementMap map = sh::bake_displacement_map(onto_input, 3);
  const auto dir = std::filesystem::temp_directory_path() / "curvefem_test_displacement_map";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "map.txt").string();
  sh::write_displacement_map(path, map);
  const sh::DisplacementMap back = sh::read_displacement_map(path);
  EXPECT_EQ(back.level, 3);
  EXPECT_EQ(back.faces, map.faces);
  ASSERT_EQ(back.h.size(), map.h.size());
  for (std::size_t i = 0; i < map.h.size(); ++i) ASSERT_EQ(back.h[i], map.h[i]) << i;
  EXPECT_EQ(sh::reconstruct(shell, back).mesh.V, sh::reconstruct(shell, map).mesh.V);
  // A face line one height short, then a height out of [-1, 1]: refused, naming file and line.
  auto refuse = [&](const std::string& text, const std::string& expected) {
    const std::string bad = (dir / "bad.txt").string();
    std::ofstream(bad) << text;
    try {
      sh::read_displacement_map(bad);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const curvefem::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refuse("curvefem-displacement-map 1\nlevel 1 faces 2\n0 0 0\n0 0\n", "bad.txt:4: face 1 has 2");
  refuse("curvefem-displacement-map 1\nlevel 1 faces 1\n0 1.5 0\n", "bad.txt:3: height \"1.5\"");
  refuse("not a map\n", "bad.txt:1:");
  // A map of another shell is refused by the reconstruction.
  sh::DisplacementMap other = map;
  other.faces += 1;
  EXPECT_THROW(sh::reconstruct(shell, other), curvefem::InputError);
  std::filesystem::remove_all(dir);
}
