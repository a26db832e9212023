// Thin-part refinement of the input (meshing/shell/thin_refine.hpp) on shapes built in code: a
// plate whose input edges are far longer than it is thick is bisected until none is (same
// surface, conforming, parents exact), a sphere is left as it is, a knife-edged disc (a wedge,
// as thin at an edge's midpoint as the edge is long) is not refined forever, and compose()
// chains two refinements.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "meshing/core/adversarial.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/shell/bevel.hpp"
#include "meshing/shell/extrusion_direction.hpp"
#include "meshing/shell/thin_refine.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;

namespace {

double area(const SurfaceMesh& s, int f) {
  const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
  return 0.5 * (b - a).cross(c - a).norm();
}

// Every directed edge once and its reverse once: closed, edge-manifold, consistently oriented.
void expect_closed_oriented(const SurfaceMesh& s) {
  std::map<std::pair<int, int>, int> directed;
  for (int f = 0; f < s.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) ++directed[{s.F(f, c), s.F(f, (c + 1) % 3)}];
  for (const auto& [e, n] : directed) {
    ASSERT_EQ(n, 1) << "edge " << e.first << "-" << e.second;
    ASSERT_EQ(directed.count({e.second, e.first}), 1u) << "edge " << e.first << "-" << e.second;
  }
}

// Edges whose two faces meet at more than 60 degrees.
std::vector<std::array<int, 2>> sharp_edges(const SurfaceMesh& s) {
  std::map<std::pair<int, int>, std::vector<int>> faces_of;
  for (int f = 0; f < s.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = s.F(f, c), b = s.F(f, (c + 1) % 3);
      faces_of[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  auto normal = [&](int f) {
    const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    return Eigen::Vector3d((b - a).cross(c - a).normalized());
  };
  std::vector<std::array<int, 2>> out;
  for (const auto& [e, fs] : faces_of)
    if (normal(fs[0]).dot(normal(fs[1])) < 0.5) out.push_back({e.first, e.second});
  return out;
}

// The edges of a mesh as (smaller id, larger id).
std::set<std::pair<int, int>> edge_set(const SurfaceMesh& s) {
  std::set<std::pair<int, int>> edges;
  for (int f = 0; f < s.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = s.F(f, c), b = s.F(f, (c + 1) % 3);
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  return edges;
}

// The refined surface is the input: input vertices unchanged and first, every refined corner at
// its barycentric place in its parent, the parents' areas split exactly among their children.
void expect_same_surface(const SurfaceMesh& input, const sh::BeveledSurface& r) {
  ASSERT_EQ(r.input_vertices, input.num_vertices());
  ASSERT_EQ(r.input_faces, input.num_faces());
  for (int v = 0; v < input.num_vertices(); ++v)
    ASSERT_EQ(r.mesh.V.row(v), input.V.row(v)) << "input vertex " << v << " moved";
  std::vector<double> child_area(std::size_t(input.num_faces()), 0);
  for (int f = 0; f < r.mesh.num_faces(); ++f) {
    const int p = r.face_parent[std::size_t(f)];
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d w = r.corner_bary[std::size_t(f)].col(c);
      EXPECT_NEAR(w.sum(), 1.0, 1e-15);
      EXPECT_GE(w.minCoeff(), 0.0);
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int i = 0; i < 3; ++i) x += w[i] * input.V.row(input.F(p, i)).transpose();
      EXPECT_LE((x - r.mesh.V.row(r.mesh.F(f, c)).transpose()).norm(), 1e-15)
          << "face " << f << " corner " << c;
    }
    child_area[std::size_t(p)] += area(r.mesh, f);
  }
  for (int p = 0; p < input.num_faces(); ++p)
    EXPECT_NEAR(child_area[std::size_t(p)], area(input, p), 1e-14) << "input face " << p;
}

}  // namespace

TEST(ThinRefine, APlateFarThinnerThanItsEdgesIsBisectedUntilNoEdgeIsThin) {
  // 1 x 1 x 0.02, 4 x 4 quads per side: top and bottom edges 0.25 (diagonals 0.35), 12 to 18
  // times the thickness; the guard's ratio is 8.
  const SurfaceMesh plate = curvefem::make_box({0, 0, 0}, {1, 1, 0.02}, 4);
  sh::ThinRefineOptions o;
  sh::ThinRefineStats st;
  const sh::BeveledSurface r = sh::refine_thin_parts(plate, o, st);
  std::printf("%d thin edges (worst %.3g) -> %d (worst %.3g), %d bisections, %d rounds, %d faces\n",
              st.thin_edges_before, st.max_ratio_before, st.thin_edges_after, st.max_ratio_after,
              st.splits, st.rounds, r.mesh.num_faces());
  ASSERT_TRUE(r.refined());
  EXPECT_GT(st.thin_edges_before, 100);
  EXPECT_GT(st.max_ratio_before, 17.0);  // a diagonal: 0.354 / 0.02
  EXPECT_EQ(st.thin_edges_after, 0);
  EXPECT_LE(st.max_ratio_after, 8.0);
  EXPECT_FALSE(st.budget_reached);
  // The top and bottom (2 x 32 faces) and the rims' 0.25-long edges are refined; each bisection
  // adds 2 faces and 1 vertex.
  EXPECT_EQ(r.mesh.num_faces(), plate.num_faces() + 2 * st.splits);
  EXPECT_EQ(r.mesh.num_vertices(), plate.num_vertices() + st.splits);
  EXPECT_EQ(st.refined_faces, r.beveled_faces);
  EXPECT_GE(st.refined_faces, 64);
  expect_closed_oriented(r.mesh);
  expect_same_surface(plate, r);

  // With the box's sharp edges kept (the mesher passes the feature edges): none of them is
  // bisected, the rest still is.
  o.kept_edges = sharp_edges(plate);
  ASSERT_EQ(o.kept_edges.size(), 4u * 3u * 4u);  // 12 box edges of 4 segments
  sh::ThinRefineStats kst;
  const sh::BeveledSurface k = sh::refine_thin_parts(plate, o, kst);
  EXPECT_GT(kst.splits, 0);
  const std::set<std::pair<int, int>> edges = edge_set(k.mesh);
  for (const auto& e : o.kept_edges)
    EXPECT_TRUE(edges.count({std::min(e[0], e[1]), std::max(e[0], e[1])}))
        << "kept edge " << e[0] << "-" << e[1] << " was bisected";
  expect_closed_oriented(k.mesh);
  expect_same_surface(plate, k);
}

// Worst 2-D MIPS of the faces of s, (|e0|² + |e1|² + |e2|²) / (2√3 area): 2 when equilateral.
double worst_mips(const SurfaceMesh& s) {
  double worst = 0;
  for (int f = 0; f < s.num_faces(); ++f) {
    const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    const double sum = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
    worst = std::max(worst, sum / (4 * std::sqrt(3.0) * area(s, f)));
  }
  return worst;
}

TEST(ThinRefine, NoRefinedFaceBecomesASliver) {
  // Generated shapes whose refinement, with their sharp edges kept (as the mesher keeps feature
  // edges), cut faces again and again along an edge that is never bisected: refined faces of
  // 2-D MIPS 1e6-1e9 (slivers along a CAD edge; shape_occt at ratio 3 kept one, 90 long and
  // 1.6e-4 high, in its coarse surface: min scaled Jacobian 2.5e-7). With the shape check
  // (max_child_mips) and the longest-edge closure no refined face is worse than twice the
  // input's worst or 40; without the check they are the slivers above.
  struct Case {
    const char* name;
    double ratio;
  };
  for (const Case c : {Case{"box_thin_long", 3}, Case{"thin_plate_05", 8},
                       Case{"split_ring_thin", 8}, Case{"noise_sphere_20", 8}}) {
    const SurfaceMesh m = curvefem::make_adversarial(c.name);
    sh::ThinRefineOptions o;
    o.max_edge_per_thickness = c.ratio;
    o.kept_edges = sharp_edges(m);
    const double input_worst = worst_mips(m);
    o.max_child_mips = 0;
    sh::ThinRefineStats off;
    const sh::BeveledSurface unchecked = sh::refine_thin_parts(m, o, off);
    o.max_child_mips = 20;
    sh::ThinRefineStats on;
    const sh::BeveledSurface checked = sh::refine_thin_parts(m, o, on);
    std::printf(
        "%s, ratio %g: input worst MIPS %.3g; unchecked %d bisections, worst %.3g; "
        "checked %d bisections (%d closure, %d left out), worst %.3g; thin edges %d -> "
        "%d\n",
        c.name, c.ratio, input_worst, off.splits, worst_mips(unchecked.mesh), on.splits,
        on.closure_splits, on.shape_refusals, worst_mips(checked.mesh), on.thin_edges_before,
        on.thin_edges_after);
    SCOPED_TRACE(c.name);
    EXPECT_GT(worst_mips(unchecked.mesh), 1e6);  // the defect the check prevents
    ASSERT_TRUE(checked.refined());
    EXPECT_GT(on.shape_refusals, 0);
    EXPECT_GT(on.splits, 0);
    EXPECT_LE(worst_mips(checked.mesh), 2 * std::max(20.0, input_worst));
    EXPECT_EQ(off.shape_refusals, 0);
    expect_closed_oriented(checked.mesh);
    expect_same_surface(m, checked);
  }
}

TEST(ThinRefine, ASphereHasNoThinEdgeAndIsReturnedAsItIs) {
  const SurfaceMesh sphere = curvefem::make_icosphere(3);
  sh::ThinRefineStats st;
  const sh::BeveledSurface r = sh::refine_thin_parts(sphere, {}, st);
  EXPECT_FALSE(r.refined());
  EXPECT_EQ(st.thin_edges_before, 0);
  EXPECT_EQ(st.splits, 0);
  EXPECT_EQ(r.mesh.V, sphere.V);
  EXPECT_EQ(r.mesh.F, sphere.F);
  // Off: nothing is measured.
  sh::ThinRefineOptions off;
  off.max_edge_per_thickness = 0;
  const sh::BeveledSurface p =
      sh::refine_thin_parts(curvefem::make_box({0, 0, 0}, {1, 1, 0.01}, 2), off, st);
  EXPECT_FALSE(p.refined());
  EXPECT_EQ(st.thin_edges_before, 0);
}

TEST(ThinRefine, AKnifeEdgeIsNotBisectedForever) {
  // The disc's rim is a 0.4° wedge: an edge running into it is as thin at its midpoint as it is
  // long, so bisecting it gains nothing (min_gain) and the refinement stops well inside the
  // budget, with thin edges left. (Before the rule that a face's thin edge must be its longest
  // to be bisected, the tangential edges next to the rim were halved until the 20,000-face
  // budget ran out.)
  const SurfaceMesh disc = curvefem::make_adversarial("knife_disc");
  sh::ThinRefineOptions o;
  sh::ThinRefineStats st;
  const sh::BeveledSurface r = sh::refine_thin_parts(disc, o, st);
  std::printf("%d thin edges -> %d, %d bisections in %d rounds\n", st.thin_edges_before,
              st.thin_edges_after, st.splits, st.rounds);
  EXPECT_GT(st.thin_edges_before, 0);
  EXPECT_GT(st.thin_edges_after, 0);
  EXPECT_FALSE(st.budget_reached);
  EXPECT_LT(st.splits, 4 * disc.num_faces());
  expect_closed_oriented(r.mesh);
  expect_same_surface(disc, r);
}

TEST(ThinRefine, ComposedWithABevelTheRefinedFacesFindTheirInputFaces) {
  const SurfaceMesh plate = curvefem::make_box({0, 0, 0}, {1, 1, 0.02}, 2);
  sh::ThinRefineStats st;
  const sh::BeveledSurface r = sh::refine_thin_parts(plate, {}, st);
  ASSERT_TRUE(r.refined());
  const auto directions = sh::extrusion_directions(r.mesh.V, r.mesh.F);
  std::vector<char> marked(std::size_t(r.mesh.num_vertices()), 0);
  for (int v = 0; v < r.mesh.num_vertices(); v += 3) marked[std::size_t(v)] = 1;
  const sh::BeveledSurface beveled = sh::bevel_surface(r.mesh, directions, marked);
  ASSERT_TRUE(beveled.refined());
  const sh::BeveledSurface both = sh::compose(r, beveled);
  EXPECT_EQ(both.mesh.num_faces(), beveled.mesh.num_faces());
  EXPECT_GT(both.beveled_faces, 0);
  EXPECT_LE(both.beveled_faces, plate.num_faces());
  expect_closed_oriented(both.mesh);
  expect_same_surface(plate, both);
  // A point through the chain: (beveled face, b) -> (refined face, b') -> (input face, b'').
  const Eigen::Vector3d b(0.2, 0.3, 0.5);
  for (int f = 0; f < both.mesh.num_faces(); f += 7) {
    const auto [mid_face, mid_bary] = beveled.to_input(f, b);
    const auto [chain_face, chain_bary] = r.to_input(mid_face, mid_bary);
    const auto [face, bary] = both.to_input(f, b);
    EXPECT_EQ(face, chain_face);
    EXPECT_LE((bary - chain_bary).norm(), 1e-15);
  }
}

namespace {

double mips(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return ((b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm()) /
         (std::sqrt(3.0) * (b - a).cross(c - a).norm());
}

// Faces with a 2-D MIPS above `limit` whose longest edge is longer than `min_edge` (counted here,
// independently of the refinement).
int poor_faces(const SurfaceMesh& s, double limit, double min_edge) {
  int n = 0;
  for (int f = 0; f < s.num_faces(); ++f) {
    const Eigen::Vector3d a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    n += longest > min_edge && mips(a, b, c) > limit;
  }
  return n;
}

// A CAD-style cylinder (radius 1, height h, n rim vertices): each side quad two needles, each cap
// a fan from one rim vertex (no vertex inside a cap), outward oriented.
SurfaceMesh fan_cylinder(int n, double h) {
  SurfaceMesh s;
  s.V.resize(2 * n, 3);
  for (int i = 0; i < n; ++i) {
    const double t = 2 * M_PI * i / n;
    s.V.row(i) << std::cos(t), std::sin(t), 0;
    s.V.row(n + i) << std::cos(t), std::sin(t), h;
  }
  std::vector<Eigen::Vector3i> F;
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    F.emplace_back(i, j, n + j);
    F.emplace_back(i, n + j, n + i);
  }
  for (int i = 1; i + 1 < n; ++i) {
    F.emplace_back(0, i + 1, i);          // bottom, facing -z
    F.emplace_back(n, n + i, n + i + 1);  // top, facing +z
  }
  s.F.resize(Eigen::Index(F.size()), 3);
  for (std::size_t f = 0; f < F.size(); ++f) s.F.row(Eigen::Index(f)) = F[f].transpose();
  return s;
}

}  // namespace

TEST(ShapeRefine, NeedleAndCapFansAreBisectedUntilNoLongFaceIsPoorlyShaped) {
  // 48 rim vertices, height 4: the side needles are 4 long and 0.13 wide (MIPS about 35), the
  // caps' fans from one rim vertex have chords up to 2 long.
  const SurfaceMesh cyl = fan_cylinder(48, 4.0);
  expect_closed_oriented(cyl);
  sh::ShapeRefineOptions o;
  o.min_edge = 0.5;
  o.max_mips = 20;
  o.feature_edges = sharp_edges(cyl);
  o.min_cone_angle = M_PI / 2;             // no fan apex is a spike tip
  ASSERT_EQ(o.feature_edges.size(), 96u);  // the two rims
  sh::ShapeRefineStats st;
  std::vector<std::array<int, 2>> features;
  const sh::BeveledSurface r = sh::refine_poor_shapes(cyl, o, st, features);
  std::printf(
      "%d poor faces -> %d, %d bisections (%d on features), %d input faces refined, %d "
      "faces\n",
      st.poor_faces_before, st.poor_faces_after, st.splits, st.feature_splits, st.refined_faces,
      r.mesh.num_faces());
  ASSERT_TRUE(r.refined());
  EXPECT_EQ(st.poor_faces_before, poor_faces(cyl, 20, 0.5));
  EXPECT_GE(st.poor_faces_before, 96);  // every side needle at least
  EXPECT_EQ(st.poor_faces_after, 0);
  EXPECT_EQ(poor_faces(r.mesh, 20, 0.5), 0);
  EXPECT_FALSE(st.budget_reached);
  EXPECT_EQ(r.mesh.num_faces(), cyl.num_faces() + 2 * st.splits);
  EXPECT_EQ(r.mesh.num_vertices(), cyl.num_vertices() + st.splits);
  EXPECT_EQ(st.refined_faces, r.beveled_faces);
  EXPECT_EQ(st.feature_splits, 0);  // the rims' edges (0.13) are never a long face's longest
  EXPECT_EQ(st.spike_faces, 0);     // the fans' apexes are rim vertices (total angle 3π/2)
  EXPECT_EQ(features.size(), o.feature_edges.size());
  expect_closed_oriented(r.mesh);
  expect_same_surface(cyl, r);

  sh::ShapeRefineOptions off = o;
  off.min_edge = 0;
  sh::ShapeRefineStats none;
  const sh::BeveledSurface same = sh::refine_poor_shapes(cyl, off, none, features);
  EXPECT_FALSE(same.refined());
  EXPECT_EQ(none.splits, 0);
  EXPECT_EQ(features.size(), o.feature_edges.size());
}

TEST(ShapeRefine, LongFeatureEdgesAreBisectedWithTheirFacesAndReturnedAsChains) {
  // An 8 x 0.25 x 0.25 bar, two triangles per side: every side face is a needle (MIPS about 37)
  // with a long box edge, which the bisections reach once the diagonals are cut.
  const SurfaceMesh bar = curvefem::make_box({0, 0, 0}, {8, 0.25, 0.25}, 1);
  sh::ShapeRefineOptions o;
  o.min_edge = 1.0;
  o.max_mips = 20;
  o.feature_edges = sharp_edges(bar);
  ASSERT_EQ(o.feature_edges.size(), 12u);
  sh::ShapeRefineStats st;
  std::vector<std::array<int, 2>> features;
  const sh::BeveledSurface r = sh::refine_poor_shapes(bar, o, st, features);
  ASSERT_TRUE(r.refined());
  EXPECT_EQ(st.poor_faces_before, poor_faces(bar, 20, 1.0));
  EXPECT_EQ(st.poor_faces_after, 0);
  EXPECT_GT(st.feature_splits, 0);
  EXPECT_EQ(features.size(), o.feature_edges.size() + std::size_t(st.feature_splits));
  expect_closed_oriented(r.mesh);
  expect_same_surface(bar, r);
  // The refined feature edges are edges of the refined surface, each on one input feature edge,
  // and together exactly as long as the input's.
  const std::set<std::pair<int, int>> edges = edge_set(r.mesh);
  double input_length = 0, refined_length = 0;
  for (const auto& e : o.feature_edges) input_length += (bar.V.row(e[0]) - bar.V.row(e[1])).norm();
  for (const auto& e : features) {
    EXPECT_TRUE(edges.count({std::min(e[0], e[1]), std::max(e[0], e[1])}));
    const Eigen::Vector3d a = r.mesh.V.row(e[0]), b = r.mesh.V.row(e[1]);
    refined_length += (a - b).norm();
    bool on_one = false;
    for (const auto& g : o.feature_edges) {
      const Eigen::Vector3d p = bar.V.row(g[0]), q = bar.V.row(g[1]);
      on_one |= (q - p).cross(a - p).norm() <= 1e-12 && (q - p).cross(b - p).norm() <= 1e-12 &&
                (a - p).dot(q - p) >= 0 && (b - p).dot(q - p) >= 0 &&
                (a - p).norm() <= (q - p).norm() && (b - p).norm() <= (q - p).norm();
    }
    EXPECT_TRUE(on_one) << "refined feature " << e[0] << "-" << e[1];
  }
  EXPECT_NEAR(refined_length, input_length, 1e-12);

  // Without feature bisection no box edge is cut; the faces whose longest edge is one stay.
  o.bisect_features = false;
  sh::ShapeRefineStats kst;
  const sh::BeveledSurface k = sh::refine_poor_shapes(bar, o, kst, features);
  EXPECT_EQ(kst.feature_splits, 0);
  EXPECT_EQ(features.size(), o.feature_edges.size());
  const std::set<std::pair<int, int>> kedges = edge_set(k.mesh);
  for (const auto& e : o.feature_edges)
    EXPECT_TRUE(kedges.count({std::min(e[0], e[1]), std::max(e[0], e[1])}));
  EXPECT_GT(kst.poor_faces_after, 0);
  expect_closed_oriented(k.mesh);
  expect_same_surface(bar, k);
}

TEST(ShapeRefine, TheSidesOfSpikesAreLeftAloneAndCountedAsSpikeFaces) {
  // Eight needles 0.3 long leaning 0.4° out of a sphere: their sides are needles whose sharpest
  // corner is the tip (total face angle about 2π sin 0.4° = 0.044). Bisecting them only adds
  // needles to the spike.
  const SurfaceMesh spiky = curvefem::make_adversarial("needle_sphere_8");
  sh::ShapeRefineOptions o;
  o.min_edge = 0.1;
  o.max_mips = 20;
  o.min_cone_angle = M_PI / 2;
  sh::ShapeRefineStats st;
  std::vector<std::array<int, 2>> features;
  const sh::BeveledSurface r = sh::refine_poor_shapes(spiky, o, st, features);
  std::printf("%d poor faces, %d at spike tips, %d bisections, %d left\n", st.poor_faces_before,
              st.spike_faces, st.splits, st.poor_faces_after);
  EXPECT_EQ(st.poor_faces_before, poor_faces(spiky, 20, 0.1));
  EXPECT_GT(st.spike_faces, 0);
  EXPECT_EQ(st.poor_faces_after, st.spike_faces);  // every other poor face was refined away
  expect_same_surface(spiky, r);
  // Without the rule the spikes' sides are bisected too.
  sh::ShapeRefineOptions all = o;
  all.min_cone_angle = 0;
  sh::ShapeRefineStats every;
  sh::refine_poor_shapes(spiky, all, every, features);
  EXPECT_EQ(every.spike_faces, 0);
  EXPECT_GT(every.splits, st.splits);
}
