// check_surface on tiny meshes built in code: every defect class with exact counts.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "meshing/check/check_surface.hpp"
#include "meshing/check/self_intersections.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"

namespace curvefem::check {
namespace {

SurfaceMesh from_lists(const std::vector<Eigen::Vector3d>& points,
                       const std::vector<std::array<int, 3>>& faces) {
  SurfaceMesh m;
  m.V.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i) m.V.row(i) = points[i].transpose();
  m.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) m.F(f, k) = faces[f][k];
  return m;
}

// Concatenates b after a (vertex ids of b shifted).
SurfaceMesh concatenate(const SurfaceMesh& a, const SurfaceMesh& b) {
  SurfaceMesh m;
  m.V.resize(a.V.rows() + b.V.rows(), 3);
  m.V << a.V, b.V;
  m.F.resize(a.F.rows() + b.F.rows(), 3);
  m.F << a.F, (b.F.array() + a.num_vertices()).matrix();
  return m;
}

std::vector<std::string> kinds(const CheckReport& r) {
  std::vector<std::string> k;
  for (const Defect& d : r.defects) k.push_back(d.kind);
  return k;
}

const Defect* find_defect(const CheckReport& r, const std::string& kind) {
  for (const Defect& d : r.defects)
    if (d.kind == kind) return &d;
  return nullptr;
}

// Unit tetrahedron scaled by 2, faces outward.
SurfaceMesh tetrahedron() {
  return from_lists({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}},
                    {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

TEST(CheckSurface, IcosphereIsAcceptableGenus0) {
  const CheckReport r = check_surface(make_icosphere(2));
  EXPECT_TRUE(r.acceptable);
  EXPECT_TRUE(r.defects.empty());
  EXPECT_EQ(r.vertices, 162);
  EXPECT_EQ(r.faces, 320);
  EXPECT_EQ(r.components, 1);
  EXPECT_TRUE(r.closed && r.edge_manifold && r.vertex_manifold && r.consistently_oriented);
  EXPECT_EQ(r.orientation_sign, 1);
  EXPECT_EQ(r.genus, 0);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_EQ(r.degenerate_faces, 0);
  EXPECT_TRUE(r.self_intersections_checked);
  EXPECT_TRUE(r.self_intersections_mesh_api);
  EXPECT_EQ(r.self_intersecting_pairs, 0);
  EXPECT_TRUE(r.volume_bounded);
  EXPECT_GT(r.min_angle_deg, 40.0);
  EXPECT_LT(r.max_angle_deg, 80.0);
  EXPECT_TRUE(r.warnings.empty());
}

// Warnings (CheckReport::warnings) do not make a surface unacceptable; they name what bounds the
// elements of any mesh whose boundary keeps it. A flat tetrahedron of height 0.02 over a base of
// legs 2: its three base edges are folds (face normals turning by 177.7°, 177.7° and 178.4°; the
// hypotenuse is the sharpest), its faces are not needles.
TEST(CheckSurface, AFlatTetrahedronIsAcceptableAndWarnsOfItsThreeFolds) {
  const SurfaceMesh m = from_lists({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, 0.02}},
                                   {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  const CheckReport r = check_surface(m);
  EXPECT_TRUE(r.acceptable);
  ASSERT_EQ(r.warnings.size(), 1u);
  const Defect& w = r.warnings[0];
  EXPECT_EQ(w.kind, "near_fold");
  EXPECT_EQ(w.count, 3);
  EXPECT_EQ(w.id_kind, "edge");
  EXPECT_EQ(w.ids, (std::vector<long long>{1, 2, 0, 1, 0, 2}));  // worst first
  EXPECT_NE(w.message.find("worst normal turn 178.4 deg at (1, 1, 0)"), std::string::npos)
      << w.message;
  // The thresholds are options: at 179° nothing is flagged.
  CheckOptions o;
  o.fold_angle_deg = 179.0;
  EXPECT_TRUE(check_surface(m, o).warnings.empty());
}

// A tetrahedron whose base (0, 2, 1) has corner angles of 0.573°: a needle face, and the
// tetrahedron is flat across it too (the faces on edges 0-3 and 1-3 turn by 179.2°).
TEST(CheckSurface, ANeedleFaceIsNamedWithItsAngle) {
  const SurfaceMesh m = from_lists({{0, 0, 0}, {2, 0, 0}, {1, 0.01, 0}, {1, 0, 1}},
                                   {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  const CheckReport r = check_surface(m);
  EXPECT_TRUE(r.acceptable);
  ASSERT_EQ(r.warnings.size(), 2u);
  EXPECT_EQ(r.warnings[0].kind, "needle");
  EXPECT_EQ(r.warnings[0].count, 1);
  EXPECT_EQ(r.warnings[0].ids, std::vector<long long>{0});
  EXPECT_NE(r.warnings[0].message.find("worst corner angle 0.5729 deg"), std::string::npos)
      << r.warnings[0].message;
  EXPECT_EQ(r.warnings[1].kind, "near_fold");
  EXPECT_EQ(r.warnings[1].ids, (std::vector<long long>{0, 3, 1, 3}));
  EXPECT_NEAR(r.min_angle_deg, 0.5729, 1e-4);
  CheckOptions o;
  o.needle_angle_deg = 0.5;
  o.fold_angle_deg = 179.5;
  EXPECT_TRUE(check_surface(m, o).warnings.empty());
}

TEST(CheckSurface, TorusHasGenus1) {
  const CheckReport r = check_surface(make_torus(2.0, 0.5, 24, 12));
  EXPECT_TRUE(r.acceptable);
  EXPECT_EQ(r.genus, 1);
  EXPECT_EQ(r.euler_characteristic, 0);
  EXPECT_EQ(r.components, 1);
}

TEST(CheckSurface, TwoDisjointSpheresHaveTwoComponents) {
  const SurfaceMesh m = concatenate(make_icosphere(1), make_icosphere(1, 1.0, {3.0, 0.0, 0.0}));
  const CheckReport r = check_surface(m);
  EXPECT_TRUE(r.acceptable);
  EXPECT_EQ(r.components, 2);
  EXPECT_EQ(r.genus, 0);
  EXPECT_EQ(r.euler_characteristic, 4);
}

TEST(CheckSurface, BoxWithoutTopSideIsOpen) {
  const int n = 2;
  const SurfaceMesh box = make_box({0, 0, 0}, {1, 1, 1}, n);
  SurfaceMesh m;
  m.V = box.V;
  std::vector<int> keep;
  for (int f = 0; f < box.num_faces(); ++f)
    if (box.tags(f) != 6) keep.push_back(f);
  m.F.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t i = 0; i < keep.size(); ++i) m.F.row(i) = box.F.row(keep[i]);
  ASSERT_EQ(m.num_faces(), 12 * n * n - 2 * n * n);

  const CheckReport r = check_surface(m);
  EXPECT_FALSE(r.acceptable);
  EXPECT_FALSE(r.closed);
  EXPECT_EQ(r.boundary_edges, 4 * n);
  EXPECT_EQ(r.unreferenced_vertices, (n - 1) * (n - 1));  // the top side's interior vertices
  EXPECT_EQ(r.genus, -1);
  EXPECT_EQ(r.orientation_sign, 0);
  EXPECT_EQ(kinds(r), std::vector<std::string>{"open"});
  const Defect* d = find_defect(r, "open");
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->count, 4 * n);
  EXPECT_EQ(d->id_kind, "edge");
  EXPECT_EQ(d->ids.size(), 2u * 4 * n);
  EXPECT_EQ(d->message.rfind("8 boundary edges (surface is open): ", 0), 0u) << d->message;
}

TEST(CheckSurface, FlippedSphereIsInward) {
  SurfaceMesh m = make_icosphere(1);
  m.F.col(1).swap(m.F.col(2));
  const CheckReport r = check_surface(m);
  EXPECT_FALSE(r.acceptable);
  EXPECT_TRUE(r.closed && r.consistently_oriented);
  EXPECT_EQ(r.orientation_sign, -1);
  EXPECT_LT(r.signed_volume, 0.0);
  EXPECT_EQ(r.genus, 0);
  EXPECT_EQ(kinds(r), std::vector<std::string>{"inward"});
  EXPECT_NE(r.defects[0].message.find("flip all faces"), std::string::npos);
}

TEST(CheckSurface, OneFlippedFaceGivesThreeInconsistentEdges) {
  SurfaceMesh m = make_icosphere(1);
  std::swap(m.F(7, 1), m.F(7, 2));
  const CheckReport r = check_surface(m);
  EXPECT_FALSE(r.acceptable);
  EXPECT_EQ(r.inconsistent_edges, 3);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_TRUE(r.orientable);
  EXPECT_EQ(r.faces_to_flip, 1);
  EXPECT_EQ(r.orientation_sign, 0);
  EXPECT_EQ(r.genus, 0);  // orientable closed manifold
  EXPECT_FALSE(r.self_intersections_mesh_api);
  EXPECT_EQ(r.self_intersecting_pairs, 0);
  EXPECT_EQ(kinds(r), std::vector<std::string>{"orientation"});
  EXPECT_NE(r.defects[0].message.find("flip 1 faces"), std::string::npos) << r.defects[0].message;
}

TEST(CheckSurface, OverlappingSpheresSelfIntersect) {
  const SurfaceMesh m = concatenate(make_icosphere(2), make_icosphere(2, 1.0, {1.0, 0.0, 0.0}));
  const CheckReport r = check_surface(m);
  EXPECT_FALSE(r.acceptable);
  EXPECT_TRUE(r.closed && r.edge_manifold && r.vertex_manifold && r.consistently_oriented);
  EXPECT_TRUE(r.self_intersections_mesh_api);
  EXPECT_GT(r.self_intersecting_pairs, 0);
  EXPECT_FALSE(r.volume_bounded);
  EXPECT_EQ(kinds(r), std::vector<std::string>{"self_intersection"});
  EXPECT_EQ(r.defects[0].ids.size(), 20u);  // 10 pairs listed

  // The soup rule gives exactly PMP's pairs on a mesh.
  const std::vector<char> degenerate = exactly_degenerate_faces(m.V, m.F);
  const auto mesh_pairs =
      find_self_intersections(m.V, m.F, degenerate, true, SelfIntersectionEngine::mesh);
  const auto soup_pairs =
      find_self_intersections(m.V, m.F, degenerate, true, SelfIntersectionEngine::soup);
  EXPECT_TRUE(mesh_pairs.used_mesh_api);
  EXPECT_FALSE(soup_pairs.used_mesh_api);
  EXPECT_EQ(mesh_pairs.pairs, soup_pairs.pairs);
  EXPECT_EQ(static_cast<long long>(mesh_pairs.pairs.size()), r.self_intersecting_pairs);

  // Each pair is one face of each sphere.
  for (const auto& [f, g] : mesh_pairs.pairs) {
    EXPECT_LT(f, 320);
    EXPECT_GE(g, 320);
  }
}

// Two triangles with one common vertex intersect when an edge of either, opposite that vertex,
// meets the other triangle: the soup rule tests both ways (each side alone decides one case).
TEST(CheckSurface, SoupRuleOnTrianglesSharingOneVertex) {
  auto pairs = [](const std::vector<Eigen::Vector3d>& g_corners) {
    Eigen::MatrixXd V(5, 3);
    V << 0, 0, 0, 1, 0, 0, 0, 1, 0, g_corners[0].transpose(), g_corners[1].transpose();
    Eigen::MatrixXi F(2, 3);
    F << 0, 1, 2, 0, 3, 4;
    return find_self_intersections(V, F, exactly_degenerate_faces(V, F), true,
                                   SelfIntersectionEngine::soup)
        .pairs.size();
  };
  // g's far edge pierces f.
  EXPECT_EQ(pairs({{0.3, 0.3, -1}, {0.3, 0.3, 1}}), 1u);
  // g's far edge passes beside f (disjoint boxes), but g cuts f's far edge at (½, ½, 0).
  EXPECT_EQ(pairs({{2, 2, -1}, {2, 2, 1}}), 1u);
  // The same, g turned away from f: only the common vertex.
  EXPECT_EQ(pairs({{-2, -2, -1}, {-2, -2, 1}}), 0u);
  // A flat fan: f and g meet at the vertex only.
  EXPECT_EQ(pairs({{-1, 0, 0}, {0, -1, 0}}), 0u);
  // Flat and overlapping: g covers part of f.
  EXPECT_EQ(pairs({{1, 1, 0}, {0.2, 1, 0}}), 1u);
}

TEST(CheckSurface, TetsSharingOneVertexArePinched) {
  SurfaceMesh m = tetrahedron();
  // Second tetrahedron: the first one mirrored through vertex 0 (orientation restored).
  SurfaceMesh mirrored = tetrahedron();
  mirrored.V = -mirrored.V;
  mirrored.F.col(1).swap(mirrored.F.col(2));
  SurfaceMesh both = concatenate(m, mirrored);
  // Weld the second copy of vertex 0 (both at the origin) onto vertex 0.
  for (int f = 4; f < 8; ++f)
    for (int k = 0; k < 3; ++k)
      if (both.F(f, k) == 4) both.F(f, k) = 0;

  const CheckReport r = check_surface(both);
  EXPECT_FALSE(r.acceptable);
  EXPECT_EQ(r.non_manifold_vertices, 1);
  EXPECT_EQ(r.unreferenced_vertices, 1);
  EXPECT_EQ(r.non_manifold_edges, 0);
  EXPECT_EQ(r.components, 2);
  EXPECT_TRUE(r.closed && r.edge_manifold && r.consistently_oriented);
  EXPECT_FALSE(r.vertex_manifold);
  EXPECT_EQ(r.orientation_sign, 1);
  EXPECT_EQ(r.genus, -1);
  EXPECT_FALSE(r.self_intersections_mesh_api);
  EXPECT_EQ(r.self_intersecting_pairs, 0);  // they touch only at the shared vertex
  EXPECT_EQ(kinds(r), std::vector<std::string>{"non_manifold_vertex"});
  EXPECT_EQ(r.defects[0].ids, std::vector<long long>{0});
}

TEST(CheckSurface, ThreeFacesOnOneEdge) {
  const SurfaceMesh m = from_lists({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 1}},
                                   {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  const CheckReport r = check_surface(m);
  EXPECT_FALSE(r.acceptable);
  EXPECT_EQ(r.non_manifold_edges, 1);
  EXPECT_EQ(r.boundary_edges, 6);
  EXPECT_EQ(r.non_manifold_vertices, 0);  // the edge's ends are not pinches
  EXPECT_EQ(r.components, 1);
  EXPECT_EQ(r.self_intersecting_pairs, 0);
  EXPECT_EQ(kinds(r), (std::vector<std::string>{"open", "non_manifold_edge"}));
  EXPECT_EQ(find_defect(r, "non_manifold_edge")->ids, (std::vector<long long>{0, 1}));
  EXPECT_EQ(find_defect(r, "non_manifold_edge")->message,
            "1 non-manifold edges (more than two faces): 0-1");
}

TEST(CheckSurface, CollinearFaceInClosedSurfaceIsDegenerate) {
  // The tetrahedron with edge 0-1 split at its midpoint 4; the side (0,1,3) keeps a zero-area
  // triangle (0,4,1) along the split edge.
  const SurfaceMesh m =
      from_lists({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {1, 0, 0}},
                 {{0, 2, 4}, {2, 1, 4}, {0, 4, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  const CheckReport r = check_surface(m);
  EXPECT_FALSE(r.acceptable);
  EXPECT_TRUE(r.closed && r.edge_manifold && r.vertex_manifold && r.consistently_oriented);
  EXPECT_EQ(r.orientation_sign, 1);
  EXPECT_EQ(r.genus, 0);
  EXPECT_EQ(r.degenerate_faces, 1);
  EXPECT_EQ(r.min_angle_deg, 0.0);
  EXPECT_EQ(r.max_angle_deg, 180.0);
  // Without the zero-area face (excluded from pairs, as in PMP), faces (0,2,4) and (2,1,4) touch
  // face (0,1,3) along 0-4 and 4-1, which are not edges of (0,1,3): a T-junction, two pairs.
  EXPECT_EQ(r.self_intersecting_pairs, 2);
  EXPECT_EQ(kinds(r), (std::vector<std::string>{"degenerate", "self_intersection"}));
  EXPECT_EQ(r.defects[0].ids, std::vector<long long>{2});
  EXPECT_EQ(r.defects[1].ids, (std::vector<long long>{0, 3, 1, 3}));
}

TEST(CheckSurface, RepeatedIndexAndNearlyCollinearFaces) {
  // Face 1 repeats a vertex; face 2 is collinear only up to rounding of 0.1 + 0.2 (not exactly).
  const SurfaceMesh m = from_lists({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.1, 0.1, 0}, {0.3, 0.3, 0}},
                                   {{0, 1, 2}, {0, 0, 1}, {0, 3, 4}});
  const std::vector<char> degenerate = exactly_degenerate_faces(m.V, m.F);
  EXPECT_EQ(degenerate, (std::vector<char>{0, 1, 1}));
  SurfaceMesh near = m;
  near.V(4, 0) = 0.1 + 0.2;  // 0.30000000000000004: off the line y = x by one ulp
  EXPECT_EQ(exactly_degenerate_faces(near.V, near.F), (std::vector<char>{0, 1, 0}));
  EXPECT_EQ(check_surface(m).degenerate_faces, 2);
}

TEST(CheckSurface, UnweldedVertexAndDuplicateFace) {
  SurfaceMesh m = make_icosphere(1);
  const int n = m.num_vertices();
  // Unweld vertex 0 for one face: a copy at the bit-identical position.
  m.V.conservativeResize(n + 1, 3);
  m.V.row(n) = m.V.row(0);
  int face = -1, valence = 0;
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (m.F(f, k) == 0) {
        ++valence;
        if (face < 0) {
          face = f;
          m.F(f, k) = n;
        }
      }
  CheckReport r = check_surface(m);
  EXPECT_EQ(r.duplicate_vertices, 1);
  EXPECT_EQ(r.boundary_edges, 4);
  // The unwelded face touches every other face around vertex 0 at one point.
  EXPECT_EQ(r.self_intersecting_pairs, valence - 1);

  SurfaceMesh dup = make_icosphere(1);
  dup.F.conservativeResize(dup.num_faces() + 1, 3);
  dup.F.row(dup.num_faces() - 1) = dup.F.row(0);
  r = check_surface(dup);
  EXPECT_EQ(r.duplicate_faces, 1);
  EXPECT_EQ(r.non_manifold_edges, 3);
  EXPECT_EQ(r.self_intersecting_pairs, 1);
}

TEST(CheckSurface, EmptyAndInvalidInput) {
  const CheckReport r = check_surface(SurfaceMesh{});
  EXPECT_FALSE(r.acceptable);
  EXPECT_EQ(kinds(r), std::vector<std::string>{"empty"});

  SurfaceMesh bad = tetrahedron();
  bad.F(2, 1) = 9;
  EXPECT_THROW(check_surface(bad), InputError);
}

TEST(CheckSurface, SelfIntersectionsCanBeSkippedAndIdsLimited) {
  const SurfaceMesh m = concatenate(make_icosphere(1), make_icosphere(1, 1.0, {1.0, 0.0, 0.0}));
  CheckOptions options;
  options.self_intersections = false;
  options.max_listed_ids = 3;
  const CheckReport r = check_surface(m, options);
  EXPECT_FALSE(r.self_intersections_checked);
  EXPECT_FALSE(r.volume_bounded);
  EXPECT_TRUE(r.acceptable);  // nothing else is wrong; the report says "not checked"

  SurfaceMesh open = make_icosphere(1);
  open.F.conservativeResize(open.num_faces() - 10, 3);
  const CheckReport o = check_surface(open, options);
  ASSERT_FALSE(o.defects.empty());
  EXPECT_EQ(o.defects[0].ids.size(), 6u);
  EXPECT_NE(o.defects[0].message.find(", ..."), std::string::npos);
}

TEST(CheckSurface, ProgressReachesTheEnd) {
  std::vector<std::string> stages;
  double last = -1.0;
  check_surface(make_icosphere(1), {}, [&](std::string_view stage, double fraction) {
    if (stages.empty() || stages.back() != stage) stages.emplace_back(stage);
    last = fraction;
  });
  EXPECT_EQ(stages, (std::vector<std::string>{"check topology", "check self-intersections"}));
  EXPECT_EQ(last, 1.0);
}

}  // namespace
}  // namespace curvefem::check
