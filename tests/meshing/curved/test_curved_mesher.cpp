// Curved meshes of order 1..4 on shapes built in code: every guarantee is re-checked by the
// independent validator, and the numbers that show the mesher did its job (coarsening, curving,
// exact feature vertices, distance bound) are asserted.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "mapping/boundary_inverse.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/curved/curved_mesher.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/curved/features.hpp"
#include "meshing/shell/fibers_of.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/simplify.hpp"
#include "tests/support/test_support.hpp"

namespace cv = curvefem::meshing::curved;
namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {

struct MeshRun {
  cv::CurvedMesh mesh;
  cv::CurvedMeshStats stats;
  cv::CurvedValidation check;
};

MeshRun mesh(const SurfaceMesh& s, int order, double eps, bool features = false,
             bool chains = false) {
  cv::CurvedMeshOptions o;
  o.order = order;
  o.eps_rel = eps;
  o.threads = 2;
  if (features) o.feature_edges = cv::detect_feature_edges(s, 60);
  o.feature_chains = chains;
  MeshRun r;
  r.mesh = cv::build_curved_mesh(s, o, r.stats);
  r.check = cv::validate_curved_mesh(r.mesh.mesh, r.mesh.map, s);
  return r;
}

double mean_distance_rel(const SurfaceMesh& s, const curvefem::BoundaryMap& map) {
  double sum = 0;
  for (int v = 0; v < s.num_vertices(); ++v) sum += (map.image(v) - s.V.row(v).transpose()).norm();
  return sum / s.num_vertices() / curvefem::bbox_longest_edge(s.V);
}

}  // namespace

TEST(CurvedMesher, SimplificationKeepsEveryInputVertexWithinTheLinearBound) {
  const SurfaceMesh sphere = curvefem::make_icosphere(3);  // 1280 faces
  sh::ShellStats ss;
  const sh::Shell shell = sh::build_shell(sphere, {}, ss);
  sh::SimplifyOptions o;
  o.threads = 2;
  o.max_distance = 0.01 * curvefem::bbox_longest_edge(sphere.V);
  sh::SimplifyStats st;
  const sh::Shell coarse = sh::simplify_shell(shell, sphere, o, st);
  EXPECT_LT(coarse.F.rows(), 1280 / 2);
  EXPECT_LE(st.max_distance, o.max_distance);
  // Independent check through the projection: locate every vertex in the coarse shell.
  const sh::ShellProjection p(coarse, sphere);
  double worst = 0;
  for (int v = 0; v < sphere.num_vertices(); ++v) {
    const Eigen::Vector3d x = sphere.V.row(v);
    const auto q = p.locate(x);
    ASSERT_TRUE(q.has_value()) << "vertex " << v << " left the shell";
    const Eigen::Vector3i F = coarse.F.row(q->face);
    const int r = sh::min_rotation(F);
    const Eigen::Vector3d m = (1 - q->u - q->v) * coarse.mid.row(F[r]).transpose() +
                              q->u * coarse.mid.row(F[(r + 1) % 3]).transpose() +
                              q->v * coarse.mid.row(F[(r + 2) % 3]).transpose();
    worst = std::max(worst, (m - x).norm());
  }
  EXPECT_LE(worst, o.max_distance * (1 + 1e-12));
  EXPECT_GT(worst, 0.2 * o.max_distance) << "the bound should be what stops coarsening";
}

TEST(CurvedMesher, SphereIsValidAtEveryOrder) {
  const SurfaceMesh sphere = curvefem::make_icosphere(3);
  double linear_mean = 0;
  for (int k = 1; k <= 4; ++k) {
    const MeshRun r = mesh(sphere, k, 1e-2);
    SCOPED_TRACE("order " + std::to_string(k));
    EXPECT_TRUE(r.check.certified())
        << r.check.non_positive_tets << " non-positive, " << r.check.undecided_tets << " undecided";
    EXPECT_TRUE(r.check.boundary_ok())
        << r.check.boundary_faces_missing << " missing, " << r.check.boundary_faces_extra
        << " extra, " << r.check.boundary_self_intersections << " self-intersections";
    EXPECT_EQ(r.check.unmapped_vertices, 0);
    EXPECT_EQ(r.check.flipped_input_faces, 0);
    EXPECT_LE(r.check.max_distance_rel, 1e-2);
    EXPECT_TRUE(r.check.valid(1e-2));
    EXPECT_EQ(r.mesh.map.boundary.num_cells(), r.stats.coarse_faces);
    EXPECT_LT(r.stats.coarse_faces, 1280 / 2);
    EXPECT_EQ(r.mesh.mesh.num_cells(), r.stats.slab_tets + r.stats.interior_tets);
    const double mean = mean_distance_rel(sphere, r.mesh.map);
    // The boundary's bounds cover every boundary triangle and edge once.
    const cv::BoundaryLimits& b = r.check.boundary_limits;
    EXPECT_EQ(b.faces, r.stats.coarse_faces);
    EXPECT_EQ(2 * b.edges, 3 * b.faces);
    EXPECT_GT(b.mips_floor, 0.3);  // above an equilateral face's 1/3
    if (k == 1) {
      linear_mean = mean;
      EXPECT_EQ(r.stats.faces_fully_curved, r.stats.coarse_faces);  // nothing to blend
      // Straight tets: the validator's own measures respect the boundary's bounds.
      EXPECT_GE(r.check.max_mips, b.mips_floor);
      EXPECT_LE(r.check.min_scaled_jacobian, b.sj_ceiling);
    } else {
      EXPECT_GT(r.stats.faces_fully_curved, r.stats.coarse_faces / 2);
      EXPECT_LT(mean, 0.5 * linear_mean) << "curving must bring the boundary closer";
    }
  }
}

TEST(CurvedMesher, CubeFeatureVerticesMapExactly) {
  const SurfaceMesh box = curvefem::make_box({0, 0, 0}, {1, 1, 1}, 6);  // 432 faces
  const auto features = cv::detect_feature_edges(box, 60);
  EXPECT_EQ(features.size(), 12u * 6u);
  const MeshRun r = mesh(box, 3, 1e-2, true);
  EXPECT_TRUE(r.check.valid(1e-2))
      << r.check.non_positive_tets << " non-positive tets, " << r.check.boundary_self_intersections
      << " intersections, " << r.check.max_distance_rel << " distance";
  EXPECT_EQ(r.stats.frozen_vertices, 8 + 12 * 5);
  const auto frozen = cv::feature_vertices(box.num_vertices(), features);
  for (int v = 0; v < box.num_vertices(); ++v)
    if (frozen[v]) EXPECT_LT((r.mesh.map.image(v) - box.V.row(v).transpose()).norm(), 1e-14) << v;
  EXPECT_LT(r.stats.coarse_faces, 432);
}

// Coarsening along the feature chains: the cube's 60 edge vertices go inside the 12 coarse
// feature edges, and the validator finds both ends of all 72 input feature edges on one boundary
// edge, at every order.
TEST(CurvedMesher, CubeCoarsensAlongItsFeatureChainsAtEveryOrder) {
  const SurfaceMesh box = curvefem::make_box({0, 0, 0}, {1, 1, 1}, 6);  // 432 faces
  const MeshRun frozen = mesh(box, 3, 1e-2, true, false);
  for (int k = 1; k <= 4; ++k) {
    SCOPED_TRACE("order " + std::to_string(k));
    const MeshRun r = mesh(box, k, 1e-2, true, true);
    EXPECT_TRUE(r.check.valid(1e-2))
        << r.check.non_positive_tets << " non-positive tets, "
        << r.check.boundary_self_intersections << " intersections, " << r.check.max_distance_rel
        << " distance, " << r.check.features_off_edges << " feature edges off";
    EXPECT_EQ(r.check.feature_edges, 72);
    EXPECT_EQ(r.check.features_off_edges, 0);
    EXPECT_EQ(r.stats.snapped_vertices, 12 * 5);
    EXPECT_EQ(r.stats.coarse_faces, 12);  // the corners only
    EXPECT_LT(r.stats.chain_max_distance_rel, 1e-12);
    EXPECT_LT(r.stats.slab_tets + r.stats.interior_tets,
              (frozen.stats.slab_tets + frozen.stats.interior_tets) / 4);
  }
  EXPECT_EQ(frozen.stats.snapped_vertices, 0);
  EXPECT_EQ(frozen.check.features_off_edges, 0);
  // The check can fail: an edge vertex moved off its boundary edge in the map.
  MeshRun r = mesh(box, 2, 1e-2, true, true);
  const auto frozen_flags = cv::feature_vertices(box.num_vertices(), r.mesh.map.feature_edges);
  int x = 0;
  while (!frozen_flags[x] || std::abs(r.mesh.map.vertex_uv(x, 0)) < 1e-3 ||
         std::abs(r.mesh.map.vertex_uv(x, 1)) < 1e-3)
    ++x;  // a chain vertex with both coordinates nonzero: inside the edge u + v = 1
  r.mesh.map.vertex_uv.row(x) *= 0.5;
  const cv::CurvedValidation bad = cv::validate_curved_mesh(r.mesh.mesh, r.mesh.map, box);
  EXPECT_EQ(bad.features_off_edges, 2);  // its two feature edges
  EXPECT_FALSE(bad.valid(1e-2));
}

// Curved feature chains: the cylinder's rims snap onto chords of the coarse feature edges, and
// the curving (through P, onto the input) bends those edges back toward the circles.
TEST(CurvedMesher, CylinderRimsBecomeCurvedFeatureEdges) {
  const SurfaceMesh cyl = curvefem::make_cylinder(48, 8, 4, 2.0);
  const double unit = curvefem::bbox_longest_edge(cyl.V);
  const MeshRun r = mesh(cyl, 3, 1e-2, true, true);
  EXPECT_TRUE(r.check.valid(1e-2))
      << r.check.features_off_edges << " feature edges off, distance " << r.check.max_distance_rel;
  EXPECT_EQ(r.check.feature_edges, 96);
  EXPECT_GT(r.stats.snapped_vertices, 40);
  // Linear: the snapped rim points (on the chords) are up to the bound from the circle; curved,
  // mostly far closer (the largest stay next to faces the certificate kept blended).
  EXPECT_GT(r.stats.chain_max_distance_rel, 0.3e-2);
  std::vector<double> linear, curved;
  for (const auto& q : r.mesh.shell.reference) {
    const Eigen::Vector3d x = cyl.V.row(q.vertex), a = cyl.V.row(q.a), b = cyl.V.row(q.b);
    linear.push_back((a + q.s * (b - a) - x).norm() / unit);
    curved.push_back((r.mesh.map.image(q.vertex) - x).norm() / unit);
  }
  std::sort(linear.begin(), linear.end());
  std::sort(curved.begin(), curved.end());
  const std::size_t mid = linear.size() / 2;
  std::cout << "rim points: median distance linear " << linear[mid] << ", curved " << curved[mid]
            << " (max " << curved.back() << ") of the bbox; " << r.stats.faces_blended
            << " faces blended, fiber misses " << r.stats.fiber_misses << "\n";
  // Rim points at the edge nodes' parameters (1/3, 2/3 of a three-segment chord) map onto
  // themselves: the nodes are traced through P onto the input.
  const auto exact =
      std::count_if(curved.begin(), curved.end(), [](double d) { return d < 1e-12; });
  EXPECT_GT(3 * exact, long(curved.size()));
  EXPECT_LT(curved[mid], 0.2 * linear[mid]);
  // In the map every snapped rim point lies exactly on its coarse edge, at barycentrics s and
  // 1 − s (rounded) with an exact 0: located from its rounding instead, it lands ~1e-16 off the
  // edge here and up to 3e-9 in the thin coarse triangles of cheese.obj, past the validator's
  // tolerance (9 feature edges off the boundary's edges, exit 3).
  int on_edge = 0;
  for (const auto& q : r.mesh.shell.reference) {
    const double u = r.mesh.map.vertex_uv(q.vertex, 0), v = r.mesh.map.vertex_uv(q.vertex, 1);
    auto end = [&](double x) { return x == q.s || x == 1 - q.s; };
    on_edge += (u == 0 && end(v)) || (v == 0 && end(u)) || (u == q.s && v == 1 - q.s) ||
               (u == 1 - q.s && v == q.s);
  }
  EXPECT_EQ(on_edge, int(r.mesh.shell.reference.size()));
}

TEST(CurvedMesher, TorusIsValidAtEveryOrder) {
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.4, 40, 16);  // 1280 faces, genus 1
  for (int k = 1; k <= 4; ++k) {
    const MeshRun r = mesh(torus, k, 1e-2);
    SCOPED_TRACE("order " + std::to_string(k));
    EXPECT_TRUE(r.check.valid(1e-2))
        << r.check.non_positive_tets << " non-positive, " << r.check.undecided_tets
        << " undecided, " << r.check.boundary_self_intersections << " intersections, distance "
        << r.check.max_distance_rel;
    EXPECT_LT(r.stats.coarse_faces, 1280 / 2);
  }
}

TEST(CurvedMesher, ExteriorSharesTheCurvedSurfaceAndEndsOnTheBox) {
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.4, 40, 16);
  for (int k : {2, 3})
    for (const int edit_passes : {0, 2}) {
      SCOPED_TRACE("order " + std::to_string(k) + ", curved edits " + std::to_string(edit_passes));
      cv::CurvedMeshOptions o;
      o.order = k;
      o.exterior = true;
      o.optimize.edits.passes = edit_passes;
      cv::CurvedMeshStats stats;
      const cv::CurvedMesh m = cv::build_curved_mesh(torus, o, stats);
      const cv::CurvedValidation check = cv::validate_curved_mesh(m.mesh, m.map, torus);
      // Valid: certified tets, the inside's boundary is exactly the map's curved triangles (so the
      // curved surface is an interface shared node for node), ε holds, and every face of the whole
      // mesh's boundary lies on one side of the padded box (4 × 4 squares × 2 triangles per side).
      EXPECT_TRUE(check.valid(1e-2));
      EXPECT_TRUE(check.exterior);
      EXPECT_EQ(check.exterior_boundary_faces, 6 * 32);
      EXPECT_EQ(check.exterior_faces_off_box, 0);
      EXPECT_EQ(check.boundary_faces, m.map.boundary.num_cells());
      // Three order-k tets per coarse face on each side (no pinched vertices on a torus), as
      // stitched; the curved edits collapse and flip slab tets (each side keeps its own tags: the
      // curved surface is never crossed).
      if (edit_passes == 0) {
        EXPECT_EQ(stats.outer_slab_tets, 3 * stats.coarse_faces);
        EXPECT_EQ(stats.slab_tets, 3 * stats.coarse_faces);
      } else {
        EXPECT_GT(stats.optimize.edits.collapses + stats.optimize.edits.flips, 0);
        EXPECT_EQ(stats.optimize.edits.cells_after, m.mesh.num_cells());
      }
      EXPECT_GT(stats.exterior_tets, 0);
      EXPECT_EQ(m.mesh.num_cells(), stats.slab_tets + stats.interior_tets + stats.outer_slab_tets +
                                        stats.exterior_tets);
      // Both tags 3 and 4 present, and each side's quality is reported.
      EXPECT_EQ(check.quality_by_tag.count(3), 1u);
      EXPECT_EQ(check.quality_by_tag.count(4), 1u);
      // The box: the input's bounding box padded by 0.25 × its longest edge (2 × 1.4 for this
      // torus), pushed out only where the outer surface comes within a quarter of that; it is the
      // bounding box of the mesh.
      const Eigen::Vector3d in_lo = torus.V.colwise().minCoeff().transpose();
      const Eigen::Vector3d in_hi = torus.V.colwise().maxCoeff().transpose();
      const double pad = 0.25 * (in_hi - in_lo).maxCoeff();
      EXPECT_TRUE((stats.exterior_box_lo.array() <= in_lo.array() - pad).all());
      EXPECT_TRUE((stats.exterior_box_hi.array() >= in_hi.array() + pad).all());
      EXPECT_DOUBLE_EQ(stats.exterior_box_lo.x(), in_lo.x() - pad);  // the outer surface is far
      EXPECT_EQ(curvefem::vertex_bounding_box(m.mesh).first, stats.exterior_box_lo);
      // A higher-order node of a box face rounding past the box (a weighted mean of the face's
      // corners can): the box is that of the tets' vertices, so every face is still on it.
      curvefem::LagrangeMesh nudged = m.mesh;
      const double top = nudged.nodes.col(2).maxCoeff();
      int nudges = 0;
      for (int n = 0; n < nudged.num_nodes() && nudges == 0; ++n)
        if (nudged.nodes(n, 2) == top) {
          bool vertex = false;
          for (int c = 0; c < nudged.num_cells() && !vertex; ++c)
            for (int j = 0; j < 4; ++j) vertex |= nudged.cells(c, j) == n;
          if (!vertex) nudged.nodes(n, 2) = std::nextafter(top, HUGE_VAL), ++nudges;
        }
      ASSERT_EQ(nudges, 1);
      EXPECT_EQ(cv::validate_curved_mesh(nudged, m.map, torus).exterior_faces_off_box, 0);
    }
}

// A padding thinner than the shell: the outer slab surface reaches past the input's bounding box
// padded by 0.1% of its longest edge, so the box is pushed out to keep a quarter of the padding
// between it and the outer surface on every side, and the mesh is still valid.
TEST(CurvedMesher, ExteriorBoxIsPushedOutWhereTheOuterSurfaceComesClose) {
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.4, 40, 16);
  const Eigen::Vector3d in_lo = torus.V.colwise().minCoeff().transpose();
  const Eigen::Vector3d in_hi = torus.V.colwise().maxCoeff().transpose();
  const double unit = (in_hi - in_lo).maxCoeff(), pad = 0.001 * unit, margin = pad / 4;
  for (const bool optimize : {false, true}) {
    SCOPED_TRACE(optimize ? "optimized" : "not optimized");
    cv::CurvedMeshOptions o;
    o.order = 2;
    o.exterior = true;
    o.exterior_padding = 0.001;
    // The curved edits stay off: the outer slab layer whose corners are checked below is what
    // they do not keep (a flip with an exterior tet hands its tag to a cell reaching the box).
    o.optimize.edits.passes = 0;
    if (!optimize) o.optimize.sweeps = 0, o.optimize.flips = false;
    cv::CurvedMeshStats stats;
    const cv::CurvedMesh m = cv::build_curved_mesh(torus, o, stats);
    const cv::CurvedValidation check = cv::validate_curved_mesh(m.mesh, m.map, torus);
    EXPECT_TRUE(check.valid(1e-2));
    EXPECT_EQ(check.exterior_faces_off_box, 0);
    // Pushed out on every side: the outer surface, raised above the shell's top where coarse
    // faces are long, reaches well past the padding (measured: lo.x −1.644 against −1.403).
    EXPECT_TRUE((stats.exterior_box_lo.array() < in_lo.array() - pad).all());
    EXPECT_TRUE((stats.exterior_box_hi.array() > in_hi.array() + pad).all());
    // The outer slab's corners (tag 3): the box is set from the outer surface when the exterior
    // is filled, exactly the margin away from it on every side; the optimization afterwards
    // moves outer vertices inward only (measured gaps 0.092..0.123).
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
    for (int c = 0; c < m.mesh.num_cells(); ++c)
      if (m.mesh.cell_tags[c] == 3)
        for (int j = 0; j < 4; ++j) {
          const Eigen::Vector3d x = m.mesh.nodes.row(m.mesh.cells(c, j)).transpose();
          lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
        }
    for (int a = 0; a < 3; ++a) {
      const double below = lo[a] - stats.exterior_box_lo[a];
      const double above = stats.exterior_box_hi[a] - hi[a];
      if (optimize) {
        EXPECT_GE(below, margin * (1 - 1e-9)) << "axis " << a;
        EXPECT_GE(above, margin * (1 - 1e-9)) << "axis " << a;
      } else {
        EXPECT_NEAR(below, margin, 1e-12 * unit) << "axis " << a;
        EXPECT_NEAR(above, margin, 1e-12 * unit) << "axis " << a;
      }
    }
  }
}

// The outer slab layer is thickened like the inner one and repaired the same way: on a torus
// with a narrow hole (radius 0.08), K = 2, the coarse shell's tops cross near the hole and the
// repair pulls those outer vertices toward the middle surface (measured: 6), while elsewhere the
// outer surface is raised beyond the shell's top. The exterior fill sees the repaired outer
// surface; the validator checks the whole mesh. (The real meshes where the shell's own tops made
// Gmsh's boundary recovery fail are in test_curved_data.cpp.)
TEST(CurvedMesher, ExteriorThickensAndRepairsTheOuterSurface) {
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.92, 48, 24);
  cv::CurvedMeshOptions o;
  o.order = 2;
  o.exterior = true;
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh m = cv::build_curved_mesh(torus, o, stats);
  const cv::CurvedValidation check = cv::validate_curved_mesh(m.mesh, m.map, torus);
  std::printf("narrow torus: %d faces, outer surface %d raised, %d lowered, %d exterior tets\n",
              stats.coarse_faces, stats.outer_raised_vertices, stats.outer_lowered_vertices,
              stats.exterior_tets);
  EXPECT_TRUE(check.valid(1e-2));
  EXPECT_EQ(check.exterior_faces_off_box, 0);
  EXPECT_GT(stats.outer_lowered_vertices, 0) << "the shell's tops cross near the hole";
  EXPECT_GT(stats.outer_raised_vertices, 0) << "the outer slab layer is thickened elsewhere";
  EXPECT_GT(check.quality_by_tag.at(3).min_scaled_jacobian, 0.0);
}

TEST(CurvedMesher, BevelsACraterAndKeepsTheMapOnTheInput) {
  // The crater of tests/meshing/shell/test_shell_bevel.cpp: its own shell is no section (a
  // pinched rim edge), so the mesher bevels 10 of its 14 faces first. The boundary map and the
  // returned shell still refer to the 9 input vertices and 14 input faces.
  const SurfaceMesh s = curvefem::test::crater_mesh();
  const MeshRun r = mesh(s, 2, 1e-2);
  EXPECT_EQ(r.stats.beveled_faces, 10);
  EXPECT_TRUE(r.stats.shell_section_verified) << r.stats.shell_non_section_prisms;
  EXPECT_EQ(r.stats.input_vertices, 9);
  EXPECT_EQ(r.stats.input_faces, 14);
  EXPECT_TRUE(r.check.valid(1e-2))
      << r.check.non_positive_tets << " non-positive, " << r.check.boundary_self_intersections
      << " intersections, distance " << r.check.max_distance_rel;
  ASSERT_EQ(r.mesh.map.num_input_vertices(), 9);
  ASSERT_EQ(r.mesh.map.vertex_uv.rows(), 9);
  for (int v = 0; v < 9; ++v) {
    EXPECT_GE(r.mesh.map.vertex_face[v], 0) << v;
    EXPECT_LE((r.mesh.map.image(v) - s.V.row(v).transpose()).norm(),
              1e-2 * curvefem::bbox_longest_edge(s.V))
        << v;
  }
  for (int p : r.mesh.shell.face_parent) {
    EXPECT_GE(p, 0);
    EXPECT_LT(p, 14);
  }
  for (int x : r.mesh.shell.input_vertex) EXPECT_LT(x, 9);
}

TEST(CurvedMesher, CraterPinchPointsMapBackThroughTheShell) {
  // The crater's rim vertices 0 and 5 are singular: zero-length pillars in the coarse shell too.
  // `curvefem mesh` reports valid only if the validator passes and every input vertex v comes
  // back from φ(v): located on the curved boundary (Gauss–Newton, so (u, v) only near the pinch
  // corner) and pulled back along the shell's fibers (cmd_mesh.cpp, map_roundtrip). Near a
  // pinch corner the fiber is ~1e-16 long; the projection must still reach the input.
  const SurfaceMesh s = curvefem::test::crater_mesh();
  const double unit = curvefem::bbox_longest_edge(s.V);
  for (int order : {2, 3}) {
    const MeshRun r = mesh(s, order, 1e-2);
    EXPECT_TRUE(r.check.valid(1e-2)) << order;
    int pinches = 0;
    for (int v = 0; v < r.mesh.shell.mid.rows(); ++v)
      if (r.mesh.shell.base.row(v) == r.mesh.shell.mid.row(v) &&
          r.mesh.shell.top.row(v) == r.mesh.shell.mid.row(v)) {
        ++pinches;
        EXPECT_TRUE(r.mesh.shell.input_vertex[std::size_t(v)] == 0 ||
                    r.mesh.shell.input_vertex[std::size_t(v)] == 5);
      }
    EXPECT_EQ(pinches, 2) << order;
    const curvefem::mapping::BoundaryInverse inverse(
        r.mesh.map, curvefem::meshing::shell::fibers_of(r.mesh.shell, s), s);
    int failures = 0;
    double worst = 0;
    for (int v = 0; v < 9; ++v) {
      const auto back = inverse(r.mesh.map.image(v));
      if (!back) {
        ++failures;
        ADD_FAILURE() << "order " << order << ": input vertex " << v << " does not map back";
        continue;
      }
      worst = std::max(worst, (back->position - s.V.row(v).transpose()).norm() / unit);
    }
    // The report's condition: valid needs 0 failures and an error <= 1e-6.
    EXPECT_EQ(failures, 0) << order;
    EXPECT_LE(worst, 1e-9) << order;
  }
}

// Curving is first decided on slabs down to the shell's base; once the slab layer is deeper,
// faces below α = 1 try again. The counts are taken after that (they were once taken before the
// slab layer could lower α further, and undercounted).
TEST(CurvedMesher, DeeperSlabsLetRefusedFacesCurveAgain) {
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.25, 48, 12);
  cv::CurvedMeshOptions o;
  o.order = 3;
  o.eps_rel = 1e-2;
  o.threads = 2;
  // The linear bound: its faces may go down to α = 0, which is what recurving lifts again (faces
  // the curved-aware bound needs fully curved never take that path).
  o.curved_coarsening = false;
  std::array<cv::CurvedMeshStats, 2> stats;
  for (int recurve = 0; recurve < 2; ++recurve) {
    o.recurve = recurve == 1;
    cv::CurvedMeshStats& s = stats[std::size_t(recurve)];
    const cv::CurvedMesh m = cv::build_curved_mesh(torus, o, s);
    const cv::CurvedValidation check = cv::validate_curved_mesh(m.mesh, m.map, torus);
    SCOPED_TRACE("recurve " + std::to_string(recurve));
    EXPECT_TRUE(check.valid(1e-2));
    EXPECT_EQ(s.faces_fully_curved + s.faces_blended + s.faces_linear, s.coarse_faces);
  }
  EXPECT_EQ(stats[0].faces_recurved, 0);
  EXPECT_GT(stats[0].curve_refused_certificate, 0);  // the shape needs it
  EXPECT_GT(stats[1].faces_recurved, 0);
  // The same coarse shell (deterministic coarsening), so the counts compare face for face.
  EXPECT_EQ(stats[0].coarse_faces, stats[1].coarse_faces);
  EXPECT_GT(stats[1].faces_fully_curved, stats[0].faces_fully_curved);
}

// The quality floor of the curving (off by default): faces whose slab tets are below it take a
// smaller α where that stays certified and within ε; the result is still a valid mesh.
TEST(CurvedMesher, TheQualityFloorLowersTheCurvingOfPinchedSlabsAndStaysValid) {
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.25, 48, 12);
  cv::CurvedMeshOptions o;
  o.order = 3;
  o.eps_rel = 1e-2;
  o.threads = 2;
  o.curved_coarsening = false;  // linear bound: every face may go down to α = 0
  std::array<cv::CurvedMeshStats, 2> stats;
  for (int on = 0; on < 2; ++on) {
    o.curve_quality_floor = on ? 0.3 : 0.0;
    cv::CurvedMeshStats& s = stats[std::size_t(on)];
    const cv::CurvedMesh m = cv::build_curved_mesh(torus, o, s);
    const cv::CurvedValidation check = cv::validate_curved_mesh(m.mesh, m.map, torus);
    SCOPED_TRACE("floor " + std::to_string(o.curve_quality_floor));
    EXPECT_TRUE(check.valid(1e-2));
    EXPECT_EQ(s.faces_fully_curved + s.faces_blended + s.faces_linear, s.coarse_faces);
  }
  EXPECT_EQ(stats[0].faces_lowered_for_quality, 0);
  EXPECT_GT(stats[1].faces_lowered_for_quality, 0);
  EXPECT_EQ(stats[0].coarse_faces, stats[1].coarse_faces);  // the same coarse shell
  EXPECT_LT(stats[1].faces_fully_curved, stats[0].faces_fully_curved);
}

namespace {
// Max |p − φ(p)| / bbox edge over the degree-L lattice points of every input triangle, φ(p)
// through the returned shell's projection (P⁻¹ gives the prism coordinates; boundary triangle f
// is shell face f in the same rotated frame).
double sample_distance_rel(const cv::CurvedMesh& m, const SurfaceMesh& s, int L) {
  const sh::ShellProjection projection(m.shell, s);
  double worst = 0;
  for (int t = 0; t < s.num_faces(); ++t)
    for (int i = 0; i <= L; ++i)
      for (int j = 0; i + j <= L; ++j) {
        const Eigen::Vector3d p =
            (i * s.V.row(s.F(t, 0)) + j * s.V.row(s.F(t, 1)) + (L - i - j) * s.V.row(s.F(t, 2)))
                .transpose() /
            double(L);
        const auto q = projection.unproject(p);
        if (!q) return HUGE_VAL;
        const Eigen::Vector3d image = m.map.boundary.map(q->face, Eigen::Vector3d(q->u, q->v, 0.0));
        worst = std::max(worst, (image - p).norm());
      }
  return worst / curvefem::bbox_longest_edge(s.V);
}
}  // namespace

// ε is enforced at the input vertices; with eps_samples it also holds at lattice points of every
// input triangle, and the validator re-checks them from the map's distance points.
TEST(CurvedMesher, SamplesBoundTheDistanceBetweenInputVertices) {
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.4, 32, 12);  // 768 faces
  const double eps = 6e-3;
  cv::CurvedMeshOptions o;
  o.order = 2;
  o.eps_rel = eps;
  o.threads = 2;
  cv::CurvedMeshStats plain_stats;
  const cv::CurvedMesh plain = cv::build_curved_mesh(torus, o, plain_stats);
  const cv::CurvedValidation plain_check = cv::validate_curved_mesh(plain.mesh, plain.map, torus);
  EXPECT_TRUE(plain_check.valid(eps));
  EXPECT_EQ(plain_check.distance_points, 0);
  const double plain_gap = sample_distance_rel(plain, torus, 3);

  o.eps_samples = 3;
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh m = cv::build_curved_mesh(torus, o, stats);
  const cv::CurvedValidation check = cv::validate_curved_mesh(m.mesh, m.map, torus);
  EXPECT_TRUE(check.valid(eps));
  // 2 points per edge (576 edges) and one per face.
  EXPECT_EQ(stats.distance_points, 2 * 1152 + 768);
  EXPECT_EQ(check.distance_points, stats.distance_points);
  EXPECT_EQ(check.bad_distance_points, 0);
  EXPECT_LE(check.points_max_distance_rel, eps);
  const double gap = sample_distance_rel(m, torus, 3);
  // Measured: 450 faces without samples, whose images of the samples reach 1.04e-2 (the bound
  // held only at the vertices); 494 faces with them, samples within 5.3e-3.
  EXPECT_GT(plain_gap, eps) << "the samples are needed on this shape";
  EXPECT_LE(gap, eps);
  // φ of the samples through the shell agrees with the (face, u, v) the map stores for them.
  EXPECT_NEAR(gap, check.points_max_distance_rel, 1e-12);
  EXPECT_LT(stats.coarse_faces, 768 * 3 / 4);
}

TEST(CurvedMesher, ConstraintPointsAreEnforcedAndCheckedByTheValidator) {
  const SurfaceMesh torus = curvefem::make_torus(1.0, 0.4, 32, 12);
  const double eps = 6e-3;
  cv::CurvedMeshOptions o;
  o.order = 2;
  o.eps_rel = eps;
  o.threads = 2;
  // Face centroids of every 7th input face, and one point 1e-9 off the surface (snapped onto it).
  for (int t = 0; t < torus.num_faces(); t += 7)
    o.constraint_points.push_back(
        (torus.V.row(torus.F(t, 0)) + torus.V.row(torus.F(t, 1)) + torus.V.row(torus.F(t, 2)))
            .transpose() /
        3.0);
  o.constraint_points.push_back(torus.V.row(5).transpose() * (1 + 1e-9));
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh m = cv::build_curved_mesh(torus, o, stats);
  EXPECT_EQ(stats.distance_points, int(o.constraint_points.size()));
  const cv::CurvedValidation check = cv::validate_curved_mesh(m.mesh, m.map, torus);
  EXPECT_TRUE(check.valid(eps));
  EXPECT_EQ(check.distance_points, stats.distance_points);
  EXPECT_LE(check.points_max_distance_rel, eps);
  // The validator computes each point from its input face and barycentric coordinates: a point
  // claimed on another face, or on no face, fails it.
  curvefem::BoundaryMap moved = m.map;
  moved.point_input_face[0] =
      (moved.point_input_face[0] + torus.num_faces() / 2) % torus.num_faces();
  const cv::CurvedValidation bad = cv::validate_curved_mesh(m.mesh, moved, torus);
  EXPECT_GT(bad.points_max_distance_rel, eps);
  EXPECT_EQ(bad.points_max_distance_point, 0);
  EXPECT_FALSE(bad.valid(eps));
  moved.point_input_face[0] = -3;
  EXPECT_EQ(cv::validate_curved_mesh(m.mesh, moved, torus).bad_distance_points, 1);
  // A point off the surface is an input error naming it.
  o.constraint_points = {Eigen::Vector3d(0, 0, 0)};  // the torus's hole
  cv::CurvedMeshStats off;
  try {
    (void)cv::build_curved_mesh(torus, o, off);
    ADD_FAILURE() << "a constraint point off the surface was accepted";
  } catch (const curvefem::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("constraint point 0"), std::string::npos) << e.what();
  }
}

// Spatially varying ε (issue 22): the bound at each input vertex is ε times its factor; the
// coarsening, the curving and the validator all honour it.
TEST(CurvedMesher, ASpatiallyVaryingEpsIsHonouredAtEveryVertexAndCheckedByTheValidator) {
  const SurfaceMesh sphere = curvefem::make_icosphere(4);  // 5120 faces
  const double eps = 0.01, unit = curvefem::bbox_longest_edge(sphere.V);
  cv::CurvedMeshOptions o;
  o.order = 3;
  o.eps_rel = eps;
  o.threads = 2;
  cv::CurvedMeshStats uniform_stats;
  const cv::CurvedMesh uniform = cv::build_curved_mesh(sphere, o, uniform_stats);
  // A quarter of ε where x < 0.
  o.eps_scale.resize(std::size_t(sphere.num_vertices()));
  for (int v = 0; v < sphere.num_vertices(); ++v)
    o.eps_scale[std::size_t(v)] = sphere.V(v, 0) < 0 ? 0.25 : 1.0;
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh m = cv::build_curved_mesh(sphere, o, stats);
  const cv::CurvedValidation check = cv::validate_curved_mesh(m.mesh, m.map, sphere);
  EXPECT_TRUE(check.valid(eps));
  EXPECT_TRUE(check.eps_field);
  // Every vertex within its own bound, computed here from φ directly.
  double worst_ratio = 0;
  for (int v = 0; v < sphere.num_vertices(); ++v) {
    const double d = (m.map.image(v) - sphere.V.row(v).transpose()).norm() / unit;
    worst_ratio = std::max(worst_ratio, d / (eps * o.eps_scale[std::size_t(v)]));
  }
  EXPECT_LE(worst_ratio, 1.0);
  EXPECT_NEAR(worst_ratio * eps, check.max_scaled_distance_rel, 1e-12);
  // Boundary faces by side (centroid of the corners): more on the fine side, about as many as
  // the uniform mesh on the other.
  auto by_side = [](const curvefem::LagrangeMesh& b) {
    std::array<int, 2> n{0, 0};
    for (int f = 0; f < b.num_cells(); ++f) {
      double x = 0;
      for (int c = 0; c < 3; ++c) x += b.nodes(b.cells(f, c), 0);
      ++n[x < 0 ? 0 : 1];
    }
    return n;
  };
  const auto u = by_side(uniform.map.boundary), f = by_side(m.map.boundary);
  std::printf("boundary faces x < 0 / x >= 0: uniform %d / %d, field %d / %d\n", u[0], u[1], f[0],
              f[1]);
  EXPECT_GT(f[0], 2 * u[0]);
  EXPECT_LT(f[1], 1.5 * u[1]);
  // The uniform mesh under the field's bounds fails the validator, at a vertex with x < 0.
  curvefem::BoundaryMap claimed = uniform.map;
  claimed.eps_scale = o.eps_scale;
  const cv::CurvedValidation bad = cv::validate_curved_mesh(uniform.mesh, claimed, sphere);
  EXPECT_FALSE(bad.valid(eps));
  ASSERT_GE(bad.max_scaled_distance_vertex, 0);
  EXPECT_LT(sphere.V(bad.max_scaled_distance_vertex, 0), 0);
  EXPECT_NEAR(bad.max_distance_rel,
              cv::validate_curved_mesh(uniform.mesh, uniform.map, sphere).max_distance_rel, 1e-15);
  // Factors outside (0, 1] or of the wrong count are input errors.
  o.eps_scale[7] = 0;
  EXPECT_THROW((void)cv::build_curved_mesh(sphere, o, stats), curvefem::InputError);
  o.eps_scale.pop_back();
  EXPECT_THROW((void)cv::build_curved_mesh(sphere, o, stats), curvefem::InputError);
  claimed.eps_scale.pop_back();
  EXPECT_THROW((void)cv::validate_curved_mesh(uniform.mesh, claimed, sphere), curvefem::InputError);
}

// The curved-aware bound in the coarsening itself: every input vertex is re-checked against the
// order-3 patch of its coarse face built here through ShellProjection (P_T at the lattice nodes),
// not through the coarsening's own fiber walk.
TEST(CurvedMesher, CurvedAwareSimplificationHoldsOnTheProjectionsPatch) {
  const SurfaceMesh sphere = curvefem::make_icosphere(4);  // 5120 faces
  sh::ShellStats ss;
  const sh::Shell shell = sh::build_shell(sphere, {}, ss);
  const double eps = 0.01 * curvefem::bbox_longest_edge(sphere.V);
  sh::SimplifyOptions o;
  o.threads = 1;
  o.max_distance = eps;
  sh::SimplifyStats linear_stats;
  const sh::Shell linear = sh::simplify_shell(shell, sphere, o, linear_stats);
  o.curved_order = 3;
  o.relaxed_distance = 3 * eps;
  o.curved_distance = 0.95 * eps;
  sh::SimplifyStats st;
  const sh::Shell coarse = sh::simplify_shell(shell, sphere, o, st);
  std::cout << "[ measured ] sphere 5120 faces, eps 1%: linear bound " << linear.F.rows()
            << " faces, curved-aware (K = 3) " << coarse.F.rows() << " faces, linear distance "
            << st.max_distance / eps << " eps\n";
  EXPECT_LE(double(coarse.F.rows()), 0.6 * double(linear.F.rows()))
      << "a cubic patch needs far fewer faces";
  EXPECT_GT(st.max_distance, eps) << "the relaxed linear bound must be in use";
  EXPECT_LE(st.max_distance, 3 * eps * (1 + 1e-12));
  const sh::ShellProjection p(coarse, sphere);
  const auto& lattice = curvefem::lagrange_lattice(curvefem::CellKind::triangle, 3);
  double worst = 0;
  for (int v = 0; v < sphere.num_vertices(); ++v) {
    const Eigen::Vector3d x = sphere.V.row(v);
    const auto q = p.locate(x);
    ASSERT_TRUE(q.has_value()) << "vertex " << v << " left the shell";
    const Eigen::VectorXd phi = curvefem::lagrange_shape_values(curvefem::CellKind::triangle, 3,
                                                                Eigen::Vector3d(q->u, q->v, 0));
    Eigen::Vector3d patch = Eigen::Vector3d::Zero();
    for (std::size_t n = 0; n < lattice.size(); ++n) {
      const auto hit =
          p.project(sh::PrismPoint{q->face, lattice[n][1] / 3.0, lattice[n][2] / 3.0, 0.0});
      ASSERT_TRUE(hit.has_value()) << "face " << q->face << " node " << n;
      patch += phi[Eigen::Index(n)] * hit->position;
    }
    worst = std::max(worst, (patch - x).norm());
  }
  EXPECT_LE(worst, 0.95 * eps * (1 + 1e-9));
}

// The mesher with it (the default at order >= 2): far fewer faces than with the linear bound,
// and the independent validator finds every input vertex within ε of the curved boundary.
TEST(CurvedMesher, CurvedAwareCoarseningMeetsEpsWithFewerFaces) {
  const SurfaceMesh sphere = curvefem::make_icosphere(4);  // 5120 faces
  for (int k : {2, 3}) {
    SCOPED_TRACE("order " + std::to_string(k));
    cv::CurvedMeshOptions o;
    o.order = k;
    o.eps_rel = 1e-2;
    o.threads = 2;
    o.curved_coarsening = false;
    cv::CurvedMeshStats linear_stats;
    const cv::CurvedMesh linear = cv::build_curved_mesh(sphere, o, linear_stats);
    o.curved_coarsening = true;
    cv::CurvedMeshStats st;
    const cv::CurvedMesh curved = cv::build_curved_mesh(sphere, o, st);
    const cv::CurvedValidation check = cv::validate_curved_mesh(curved.mesh, curved.map, sphere);
    std::cout << "[ measured ] sphere 5120 faces, K = " << k << ": linear bound "
              << linear_stats.coarse_faces << " faces / " << linear.mesh.num_cells()
              << " tets; curved-aware " << st.coarse_faces << " faces / " << curved.mesh.num_cells()
              << " tets (attempt " << st.curved_attempts << "), max distance "
              << check.max_distance_rel << "\n";
    EXPECT_TRUE(check.valid(1e-2));
    EXPECT_LE(check.max_distance_rel, 1e-2);
    EXPECT_TRUE(st.curved_coarsening);
    EXPECT_GT(st.linear_max_distance_rel, 1e-2);
    EXPECT_LT(st.coarse_faces, 0.7 * linear_stats.coarse_faces);
    EXPECT_LE(linear_stats.linear_max_distance_rel, 1e-2);
    EXPECT_FALSE(linear_stats.curved_coarsening);
  }
  // Order 1 has no curved patch: the linear bound, whatever the option says.
  cv::CurvedMeshOptions o;
  o.order = 1;
  o.threads = 2;
  cv::CurvedMeshStats st;
  cv::build_curved_mesh(sphere, o, st);
  EXPECT_FALSE(st.curved_coarsening);
  EXPECT_LE(st.linear_max_distance_rel, 1e-2);
}

// ε levels from one coarsening (issue 22): the shell is built once, the finest level coarsens
// it, each coarser level resumes from the finer one's coarse shell (feature chains included);
// every level is a valid mesh under its own bound, and the finest is the single-ε mesh.
TEST(CurvedMesher, EpsLevelsComeFromOneShellAndOneCoarseningAndAreEachValid) {
  const SurfaceMesh cyl = curvefem::make_cylinder(64, 12, 6, 2.0);
  cv::CurvedMeshOptions o;
  o.order = 3;
  o.threads = 2;
  o.feature_edges = cv::detect_feature_edges(cyl, 60);
  ASSERT_FALSE(o.feature_edges.empty());
  const std::vector<cv::EpsLevel> levels = {{0.01, {}}, {0.004, {}}, {0.04, {}}};
  std::vector<cv::CurvedMeshStats> stats;
  const std::vector<cv::CurvedMesh> out = cv::build_curved_mesh_levels(cyl, o, levels, stats);
  ASSERT_EQ(out.size(), 3u);
  ASSERT_EQ(stats.size(), 3u);
  auto has_stage = [](const cv::CurvedMeshStats& s, const std::string& name) {
    return std::any_of(s.stage_seconds.begin(), s.stage_seconds.end(),
                       [&](const auto& e) { return e.first == name; });
  };
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const cv::CurvedValidation check = cv::validate_curved_mesh(out[i].mesh, out[i].map, cyl);
    EXPECT_TRUE(check.valid(levels[i].eps_rel)) << "eps " << levels[i].eps_rel;
    EXPECT_LE(check.max_distance_rel, levels[i].eps_rel);
    EXPECT_EQ(check.features_off_edges, 0);
    std::printf("eps %.4f: %d coarse faces (resumed from %d), %d chain collapses, %d tets\n",
                levels[i].eps_rel, stats[i].coarse_faces, stats[i].coarsen_start_faces,
                stats[i].coarsen_chain_collapses, out[i].mesh.num_cells());
  }
  // Finest first (level 1, ε = 0.004), from the input's shell; then 0.01 from its coarse
  // shell, then 0.04 from that of 0.01. Only the finest builds the shell.
  EXPECT_EQ(stats[1].coarsen_start_faces, 0);
  EXPECT_TRUE(has_stage(stats[1], "shell"));
  EXPECT_EQ(stats[0].coarsen_start_faces, stats[1].coarse_faces);
  EXPECT_EQ(stats[2].coarsen_start_faces, stats[0].coarse_faces);
  EXPECT_FALSE(has_stage(stats[0], "shell"));
  EXPECT_FALSE(has_stage(stats[2], "shell"));
  // Coarser with every level, the chains included (the rims keep coarsening).
  EXPECT_LT(stats[0].coarse_faces, stats[1].coarse_faces);
  EXPECT_LT(stats[2].coarse_faces, stats[0].coarse_faces);
  EXPECT_GT(stats[0].coarsen_chain_collapses + stats[2].coarsen_chain_collapses, 0);
  // The finest level is the single-ε mesh, node for node.
  cv::CurvedMeshOptions single = o;
  single.eps_rel = 0.004;
  cv::CurvedMeshStats single_stats;
  const cv::CurvedMesh one = cv::build_curved_mesh(cyl, single, single_stats);
  ASSERT_EQ(one.mesh.num_nodes(), out[1].mesh.num_nodes());
  ASSERT_EQ(one.mesh.num_cells(), out[1].mesh.num_cells());
  EXPECT_EQ((one.mesh.nodes - out[1].mesh.nodes).cwiseAbs().maxCoeff(), 0.0);
  // Repeated or non-positive levels are input errors.
  EXPECT_THROW((void)cv::build_curved_mesh_levels(cyl, o, {{0.01, {}}, {0.01, {}}}, stats),
               curvefem::InputError);
  EXPECT_THROW((void)cv::build_curved_mesh_levels(cyl, o, {{0.01, {}}, {0, {}}}, stats),
               curvefem::InputError);
  EXPECT_THROW((void)cv::build_curved_mesh_levels(cyl, o, {}, stats), curvefem::InputError);
}
