// check::merge_short_edges on surfaces built in code: a needle pair inserted into an icosphere is
// merged back exactly, a tetrahedron (every collapse breaks the manifold) is left as it is.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "meshing/check/check_surface.hpp"
#include "meshing/check/merge_short_edges.hpp"
#include "meshing/core/primitives.hpp"

namespace curvefem::check {
namespace {

double volume(const SurfaceMesh& m) {
  double v = 0;
  for (int f = 0; f < m.num_faces(); ++f)
    v += Eigen::Vector3d(m.V.row(m.F(f, 0)))
             .dot(Eigen::Vector3d(m.V.row(m.F(f, 1))).cross(Eigen::Vector3d(m.V.row(m.F(f, 2))))) /
         6.0;
  return v;
}

// The icosphere with a vertex c inserted on the edge a-b of face 0 at t of its length from a:
// faces 0 and the one across the edge become two each, the two on a-c needles.
struct Split {
  SurfaceMesh mesh;
  int a = -1, b = -1, c = -1;
};
Split split_edge(const SurfaceMesh& sphere, double t) {
  Split s;
  s.mesh = sphere;
  s.a = sphere.F(0, 0), s.b = sphere.F(0, 1);
  const int x = sphere.F(0, 2);
  int across = -1, y = -1;
  for (int f = 1; f < sphere.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (sphere.F(f, k) == s.b && sphere.F(f, (k + 1) % 3) == s.a)
        across = f, y = sphere.F(f, (k + 2) % 3);
  s.c = sphere.num_vertices();
  s.mesh.V.conservativeResize(s.c + 1, 3);
  s.mesh.V.row(s.c) = (1 - t) * sphere.V.row(s.a) + t * sphere.V.row(s.b);
  const int nf = sphere.num_faces();
  s.mesh.F.conservativeResize(nf + 2, 3);
  s.mesh.F.row(0) << s.a, s.c, x;
  s.mesh.F.row(nf) << s.c, s.b, x;
  s.mesh.F.row(across) << s.b, s.c, y;
  s.mesh.F.row(nf + 1) << s.c, s.a, y;
  s.mesh.tags.resize(nf + 2);
  for (int f = 0; f < nf + 2; ++f) s.mesh.tags(f) = f % 5;
  return s;
}

TEST(MergeShortEdges, ANeedlePairInsertedIntoASphereIsMergedBack) {
  const SurfaceMesh sphere = make_icosphere(2, 1.0);
  const Split s = split_edge(sphere, 1e-5);
  const double ac = (s.mesh.V.row(s.c) - s.mesh.V.row(s.a)).norm();
  const CheckReport before = check_surface(s.mesh, {});
  ASSERT_TRUE(before.acceptable);
  ASSERT_EQ(before.warnings.size(), 1u);
  EXPECT_EQ(before.warnings[0].kind, "needle");
  EXPECT_EQ(before.warnings[0].count, 2);  // (a, c, x) and (c, a, y)

  const MergeShortEdgesResult r = merge_short_edges(s.mesh, {.max_length = 1e-3});
  EXPECT_EQ(r.candidates, 1);
  ASSERT_EQ(r.merged.size(), 1u);
  EXPECT_EQ(r.refused, 0);
  EXPECT_DOUBLE_EQ(r.max_moved, ac);
  const MergedEdge& e = r.merged[0];
  EXPECT_TRUE((e.removed == s.c && e.kept == s.a) || (e.removed == s.a && e.kept == s.c));
  EXPECT_EQ(r.mesh.num_vertices(), sphere.num_vertices());
  EXPECT_EQ(r.mesh.num_faces(), sphere.num_faces());
  ASSERT_EQ(r.vertex_map.size(), std::size_t(s.mesh.num_vertices()));
  EXPECT_EQ(r.vertex_map[std::size_t(s.a)], r.vertex_map[std::size_t(s.c)]);
  // Every kept vertex where it was, every face one of the input's with its tag.
  for (int v = 0; v < s.mesh.num_vertices(); ++v)
    if (v != e.removed) EXPECT_EQ(r.mesh.V.row(r.vertex_map[std::size_t(v)]), s.mesh.V.row(v)) << v;
  ASSERT_EQ(r.face_origin.size(), std::size_t(r.mesh.num_faces()));
  for (int f = 0; f < r.mesh.num_faces(); ++f) {
    const int o = r.face_origin[std::size_t(f)];
    EXPECT_EQ(r.mesh.tags(f), s.mesh.tags(o));
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(r.mesh.F(f, k), r.vertex_map[std::size_t(s.mesh.F(o, k))]);
  }
  const CheckReport after = check_surface(r.mesh, {});
  EXPECT_TRUE(after.acceptable);
  EXPECT_TRUE(after.warnings.empty());
  EXPECT_NEAR(volume(r.mesh), volume(sphere), 1e-9);

  // Below the needle's short edge nothing is a candidate.
  const MergeShortEdgesResult none = merge_short_edges(s.mesh, {.max_length = 0.5 * ac});
  EXPECT_EQ(none.candidates, 0);
  EXPECT_TRUE(none.merged.empty());
  EXPECT_EQ(none.mesh.F, s.mesh.F);
}

TEST(MergeShortEdgesAndTheLinkCondition, ATetrahedronKeepsEveryEdge) {
  SurfaceMesh tet;
  tet.V.resize(4, 3);
  tet.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  tet.F.resize(4, 3);
  tet.F << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  const MergeShortEdgesResult r = merge_short_edges(tet, {.max_length = 10});
  EXPECT_EQ(r.candidates, 6);
  EXPECT_TRUE(r.merged.empty());
  EXPECT_EQ(r.refused, 6);
  EXPECT_EQ(r.mesh.V, tet.V);
  EXPECT_EQ(r.mesh.F, tet.F);
}

}  // namespace
}  // namespace curvefem::check
