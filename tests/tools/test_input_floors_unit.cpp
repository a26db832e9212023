// pipeline::input_floors on a mesh built by hand: a one-tet mesh whose boundary is its input,
// a tetrahedron with a needle base (corner angles 0.573°) that is flat across it (two edges whose
// face normals turn by 179.2°). Every flagged feature is kept, and the one tet is on them; with the
// boundary's copy of a corner moved off its input point, none is kept.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "pipeline/input_floors.hpp"

namespace curvefem::pipeline {
namespace {

struct OneTet {
  SurfaceMesh input;
  BoundaryMap map;
  LagrangeMesh mesh;
};

OneTet needle_tet() {
  OneTet t;
  t.input.V.resize(4, 3);
  t.input.V << 0, 0, 0, 2, 0, 0, 1, 0.01, 0, 1, 0, 1;
  t.input.F.resize(4, 3);
  t.input.F << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  t.map.boundary = as_triangle_mesh(t.input);
  t.map.boundary_node_to_volume = Eigen::VectorXi::LinSpaced(4, 0, 3);
  t.mesh.kind = CellKind::tetrahedron;
  t.mesh.order = 1;
  t.mesh.nodes = t.input.V;
  t.mesh.cells.resize(1, 4);
  t.mesh.cells << 0, 1, 2, 3;
  return t;
}

TEST(InputFloors, TheNeedleAndTheFoldsKeptAsBoundaryAreFoundWithTheTetOnThem) {
  const OneTet t = needle_tet();
  const InputFloors f = input_floors(t.input, t.map, t.mesh, {1234.5}, {0.004});
  EXPECT_EQ(f.needle_faces, 1);
  EXPECT_EQ(f.needle_faces_kept, 1);
  EXPECT_EQ(f.kept_needle_faces, std::vector<int>{0});
  EXPECT_EQ(f.near_fold_edges, 2);
  EXPECT_EQ(f.near_fold_edges_kept, 2);
  ASSERT_EQ(f.kept_fold_edges.size(), 2u);
  EXPECT_EQ(f.kept_fold_edges[0], (std::array<int, 2>{0, 3}));
  EXPECT_EQ(f.kept_fold_edges[1], (std::array<int, 2>{1, 3}));
  EXPECT_EQ(f.tets_at_kept, 1);
  EXPECT_EQ(f.max_mips_at_kept, 1234.5);
  EXPECT_EQ(f.min_scaled_jacobian_at_kept, 0.004);
  EXPECT_TRUE(f.worst_mips_tet_at_kept);
  EXPECT_TRUE(f.worst_scaled_jacobian_tet_at_kept);
  const auto j = input_floors_json(f);
  EXPECT_EQ(j["needle_faces_kept"], 1);
  EXPECT_EQ(j["kept_fold_edges"], nlohmann::json::parse("[[0, 3], [1, 3]]"));
  // The needle's two long sides (|(1, 0.01, 0)|) are its shortest; the bbox is 2 long. The hint
  // names a merge length just above it where that is below the distance bound, and nothing where
  // it is not.
  EXPECT_DOUBLE_EQ(f.shortest_edge_at_kept, std::sqrt(1.0001));
  EXPECT_DOUBLE_EQ(j["shortest_edge_at_kept_rel"].get<double>(), std::sqrt(1.0001) / 2);
  EXPECT_EQ(merge_hint(f, 0.01), "");
  const std::string hint = merge_hint(f, 1.0);
  EXPECT_NE(hint.find("`--merge-short-edges 0.53`"), std::string::npos) << hint;
  InputFloors elsewhere = f;  // the worst tet is not on them: no hint
  elsewhere.worst_mips_tet_at_kept = elsewhere.worst_scaled_jacobian_tet_at_kept = false;
  EXPECT_EQ(merge_hint(elsewhere, 1.0), "");
}

TEST(InputFloors, NothingIsKeptWhereTheBoundaryMovedOffTheInputPoints) {
  OneTet t = needle_tet();
  t.map.boundary.nodes(3, 2) += 1e-9;  // the apex, an end of both fold edges
  t.map.boundary.nodes(2, 1) += 1e-9;  // the needle face's tip
  const InputFloors f = input_floors(t.input, t.map, t.mesh, {1234.5}, {0.004});
  EXPECT_EQ(f.needle_faces, 1);
  EXPECT_EQ(f.near_fold_edges, 2);
  EXPECT_EQ(f.needle_faces_kept, 0);
  EXPECT_EQ(f.near_fold_edges_kept, 0);
  EXPECT_EQ(f.tets_at_kept, 0);
  EXPECT_FALSE(f.worst_mips_tet_at_kept);
  EXPECT_TRUE(input_floors_json(f)["max_mips_at_kept"].is_null());
  EXPECT_TRUE(input_floors_json(f)["shortest_edge_at_kept_rel"].is_null());
}

TEST(InputFloors, ASmoothInputHasNothingToFlag) {
  OneTet t = needle_tet();
  t.input.V.row(2) << 0, 2, 0;  // a right tetrahedron: no needle, no fold
  t.map.boundary = as_triangle_mesh(t.input);
  t.mesh.nodes = t.input.V;
  const InputFloors f = input_floors(t.input, t.map, t.mesh, {3.0}, {0.5});
  EXPECT_EQ(f.needle_faces + f.near_fold_edges + f.tets_at_kept, 0);
}

}  // namespace
}  // namespace curvefem::pipeline
