// Topological beveling (meshing/shell/bevel.hpp) on tiny meshes built in code: a crater whose
// shell fails the section condition without beveling and passes every check with it, meshes
// that need no beveling (returned bit-identical), and the refinement pattern itself.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <map>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/shell/bevel.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/verify.hpp"
#include "tests/support/test_support.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {

SurfaceMesh crater() { return curvefem::test::crater_mesh(); }

double area(const SurfaceMesh& s, int f) {
  const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
  return 0.5 * (b - a).cross(c - a).norm();
}
Eigen::Vector3d normal(const SurfaceMesh& s, int f) {
  const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
  return (b - a).cross(c - a).normalized();
}

// Closed and consistently oriented: every directed edge once, its reverse once.
void expect_closed_oriented(const SurfaceMesh& s) {
  std::map<std::pair<int, int>, int> directed;
  for (int f = 0; f < s.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) ++directed[{s.F(f, k), s.F(f, (k + 1) % 3)}];
  for (const auto& [e, n] : directed) {
    EXPECT_EQ(n, 1) << e.first << " " << e.second;
    EXPECT_EQ(directed.count({e.second, e.first}), 1u) << e.first << " " << e.second;
  }
}

// The refinement keeps the geometry: input vertices unchanged at their ids, every refined corner
// at its parent barycentrics (non-negative, summing to 1), same orientation, same total area.
void expect_same_geometry(const SurfaceMesh& input, const sh::BeveledSurface& b) {
  ASSERT_GE(b.mesh.num_vertices(), input.num_vertices());
  EXPECT_EQ(b.input_vertices, input.num_vertices());
  EXPECT_EQ(b.input_faces, input.num_faces());
  EXPECT_TRUE(b.mesh.V.topRows(input.num_vertices()) == input.V);
  ASSERT_EQ(int(b.face_parent.size()), b.mesh.num_faces());
  ASSERT_EQ(int(b.corner_bary.size()), b.mesh.num_faces());
  const double unit = curvefem::bbox_longest_edge(input.V);
  double total_in = 0, total_out = 0;
  for (int f = 0; f < input.num_faces(); ++f) total_in += area(input, f);
  for (int f = 0; f < b.mesh.num_faces(); ++f) {
    total_out += area(b.mesh, f);
    const int p = b.face_parent[std::size_t(f)];
    ASSERT_GE(p, 0);
    ASSERT_LT(p, input.num_faces());
    const Eigen::Matrix3d& M = b.corner_bary[std::size_t(f)];
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(M.col(k).minCoeff(), 0.0);
      EXPECT_NEAR(M.col(k).sum(), 1.0, 1e-15);
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int j = 0; j < 3; ++j) x += M(j, k) * Eigen::Vector3d(input.V.row(input.F(p, j)));
      EXPECT_LE((x - Eigen::Vector3d(b.mesh.V.row(b.mesh.F(f, k)))).norm(), 1e-15 * unit)
          << "face " << f << " corner " << k;
    }
    EXPECT_GT(normal(b.mesh, f).dot(normal(input, p)), 1 - 1e-12) << "face " << f;
    // to_input maps the centroid into the parent at its barycentrics.
    const auto [q, bary] = b.to_input(f, Eigen::Vector3d::Constant(1.0 / 3));
    EXPECT_EQ(q, p);
    EXPECT_NEAR(bary.sum(), 1.0, 1e-15);
  }
  EXPECT_NEAR(total_out, total_in, 1e-12 * total_in);
  expect_closed_oriented(b.mesh);
}

}  // namespace

TEST(ShellBevel, CraterNeedsBevelingAndBevelingMakesItASection) {
  const SurfaceMesh input = crater();
  const sh::ShellOptions options;

  // Without beveling: positive and separated, but not a section.
  sh::ShellStats plain_stats;
  const sh::Shell plain = sh::build_shell(input, options, plain_stats);
  EXPECT_EQ(plain_stats.singular_vertices, 2);
  EXPECT_EQ(plain_stats.pinch_splits, 1);
  const sh::ShellVerification before = sh::verify_shell(plain, input);
  EXPECT_TRUE(before.positive());
  EXPECT_TRUE(before.separated());
  EXPECT_EQ(before.non_section_faces, 2);
  EXPECT_EQ(sh::non_section_prisms(plain, input).size(), 2u);

  // With beveling: one round around the corners of the failing face (0, 5, 1).
  sh::ShellStats stats;
  const sh::BeveledShell b = sh::build_beveled_shell(input, options, stats);
  EXPECT_TRUE(b.stats.needed);
  EXPECT_EQ(b.stats.rounds, 1);
  EXPECT_EQ(b.stats.non_section_before, 2);
  EXPECT_EQ(b.stats.non_section_after, 0);
  EXPECT_EQ(b.stats.marked_vertices, 3);
  EXPECT_EQ(b.stats.beveled_faces, b.surface.beveled_faces);
  // The faces around the pit or the two rim vertices: all but 4 of the bottom faces.
  EXPECT_EQ(b.surface.beveled_faces, 10);
  EXPECT_TRUE(b.surface.refined());
  EXPECT_EQ(stats.input_faces, input.num_faces());
  EXPECT_EQ(stats.input_vertices, input.num_vertices());
  // The rim vertices stay singular, but no longer share an edge: nothing is pinch-split.
  EXPECT_EQ(stats.singular_vertices, 2);
  EXPECT_EQ(stats.pinch_splits, 0);
  expect_same_geometry(input, b.surface);

  const sh::ShellVerification after = sh::verify_shell(b.shell, b.surface.mesh);
  EXPECT_TRUE(after.positive());
  EXPECT_TRUE(after.separated());
  EXPECT_TRUE(after.section()) << after.non_section_faces;
  EXPECT_EQ(after.roundtrip_failures, 0);
  EXPECT_LE(after.roundtrip_max_error_rel, 1e-9);

  // Every new vertex has a direction that sees every face around it (for a point on an input
  // edge next to a singular corner: the sum of that edge's two face normals).
  const sh::BeveledSurface& s = b.surface;
  for (int f = 0; f < s.mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = s.mesh.F(f, k);
      if (v < input.num_vertices()) continue;
      EXPECT_FALSE(s.directions.singular[std::size_t(v)]);
      EXPECT_NEAR(s.directions.N.row(v).norm(), 1.0, 1e-12);
      EXPECT_GT(s.directions.N.row(v).dot(normal(s.mesh, f)), 0.0) << "vertex " << v;
    }

  // The shell refers back to the input after restore_input_ids.
  sh::Shell restored = b.shell;
  sh::restore_input_ids(restored, b.surface);
  for (int f = 0; f < restored.F.rows(); ++f) {
    EXPECT_GE(restored.face_parent[std::size_t(f)], 0);
    EXPECT_LT(restored.face_parent[std::size_t(f)], input.num_faces());
  }
  for (int v = 0; v < restored.mid.rows(); ++v) {
    const int x = restored.input_vertex[std::size_t(v)];
    EXPECT_LT(x, input.num_vertices());
    if (x >= 0) {
      EXPECT_TRUE(restored.mid.row(v) == input.V.row(x));
    }
  }
}

TEST(ShellBevel, MeshesThatDoNotNeedBevelingAreUnchanged) {
  for (const SurfaceMesh& input :
       {curvefem::make_icosphere(2),
        curvefem::make_box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 1), 3)}) {
    sh::ShellStats plain_stats, stats;
    const sh::Shell plain = sh::build_shell(input, sh::ShellOptions{}, plain_stats);
    const sh::BeveledShell b = sh::build_beveled_shell(input, sh::ShellOptions{}, stats);
    EXPECT_FALSE(b.stats.needed);
    EXPECT_EQ(b.stats.rounds, 0);
    EXPECT_EQ(b.stats.beveled_faces, 0);
    EXPECT_FALSE(b.surface.refined());
    EXPECT_TRUE(b.surface.mesh.V == input.V);
    EXPECT_TRUE(b.surface.mesh.F == input.F);
    EXPECT_TRUE(b.shell.base == plain.base);
    EXPECT_TRUE(b.shell.mid == plain.mid);
    EXPECT_TRUE(b.shell.top == plain.top);
    EXPECT_TRUE(b.shell.F == plain.F);
    EXPECT_EQ(b.shell.face_parent, plain.face_parent);
    EXPECT_EQ(stats.input_faces, input.num_faces());
  }
}

TEST(ShellBevel, PatternRefinesAroundMarkedVerticesOnly) {
  // Octahedron, all corners of face 0 marked: that face gets the full 13-triangle pattern, each
  // face sharing one or two marked corners a partial one, the opposite face stays whole.
  SurfaceMesh oct;
  oct.V.resize(6, 3);
  oct.V << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  oct.F.resize(8, 3);
  oct.F << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  const sh::ExtrusionDirections d = sh::extrusion_directions(oct.V, oct.F);
  std::vector<char> marked(6, 0);
  marked[0] = marked[2] = marked[4] = 1;
  const sh::BeveledSurface b = sh::bevel_surface(oct, d, marked);
  expect_same_geometry(oct, b);
  EXPECT_EQ(b.marked_vertices, 3);
  EXPECT_EQ(b.beveled_faces, 7);  // all but (1, 3, 5)
  std::vector<int> per_parent(8, 0);
  for (int p : b.face_parent) ++per_parent[std::size_t(p)];
  // Full pattern: 6 corner triangles, 6 strip triangles, 1 centre. A strip next to an unmarked
  // corner keeps 1 triangle, between two unmarked corners none; the centre is 1 triangle.
  EXPECT_EQ(per_parent[0], 13);
  EXPECT_EQ(per_parent[6], 1);                                            // no marked corner
  for (int f : {1, 3, 4}) EXPECT_EQ(per_parent[std::size_t(f)], 9) << f;  // 4 + 2 + 1 + 1 + 1
  for (int f : {2, 5, 7}) EXPECT_EQ(per_parent[std::size_t(f)], 5) << f;  // 2 + 1 + 1 + 1
  // 6 input vertices, 2 edge points per marked corner and edge (3 corners × 4 edges), one
  // inner point per marked corner and face (3 × 4).
  EXPECT_EQ(b.mesh.num_vertices(), 6 + 12 + 12);
  // Every new vertex copies the direction of the corner it was made for: the nearest input
  // vertex.
  for (int v = 6; v < b.mesh.num_vertices(); ++v) {
    int nearest = 0;
    for (int u = 1; u < 6; ++u)
      if ((oct.V.row(u) - b.mesh.V.row(v)).norm() < (oct.V.row(nearest) - b.mesh.V.row(v)).norm())
        nearest = u;
    EXPECT_TRUE(b.directions.N.row(v) == d.N.row(nearest)) << v;
  }
  // The shell of the refined octahedron with these directions is valid.
  sh::ShellStats stats;
  const sh::Shell shell = sh::build_shell(b.mesh, b.directions, sh::ShellOptions{}, stats);
  const sh::ShellVerification v = sh::verify_shell(shell, b.mesh);
  EXPECT_TRUE(v.valid()) << v.non_positive_faces << " " << v.intersecting_input_faces << " "
                         << v.non_section_faces << " " << v.roundtrip_failures;
}

TEST(ShellBevel, RejectsBadArguments) {
  const SurfaceMesh s = crater();
  const sh::ExtrusionDirections d = sh::extrusion_directions(s.V, s.F);
  EXPECT_THROW(sh::bevel_surface(s, d, std::vector<char>(3, 0)), curvefem::InputError);
  sh::BevelOptions bad;
  bad.t = 0.5;
  EXPECT_THROW(sh::bevel_surface(s, d, std::vector<char>(9, 1), bad), curvefem::InputError);
  SurfaceMesh open = s;
  open.F.conservativeResize(open.F.rows() - 1, 3);
  EXPECT_THROW(sh::bevel_surface(open, d, std::vector<char>(9, 1)), curvefem::InputError);
}
