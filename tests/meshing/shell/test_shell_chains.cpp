// Shell simplification along feature chains (thesis §5.3): chain vertices collapse along their
// coarse feature edge, the input vertices inside it are snapped onto it in the reference copy,
// and the shell stays valid for that copy (integration label).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <string>

#include "meshing/core/primitives.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"

namespace sh = curvefem::meshing::shell;
using curvefem::SurfaceMesh;
using Eigen::Vector3d;

namespace {

// Edges whose two faces' normals differ by more than `angle_deg`.
std::vector<std::array<int, 2>> sharp_edges(const SurfaceMesh& m, double angle_deg) {
  std::map<std::pair<int, int>, std::vector<int>> faces;
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = m.F(f, k), b = m.F(f, (k + 1) % 3);
      faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  auto normal = [&](int f) {
    const Vector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    return Vector3d((b - a).cross(c - a).normalized());
  };
  std::vector<std::array<int, 2>> out;
  for (const auto& [e, fs] : faces)
    if (fs.size() == 2 && normal(fs[0]).dot(normal(fs[1])) < std::cos(angle_deg * M_PI / 180))
      out.push_back({e.first, e.second});
  return out;
}

void expect_valid(const sh::Shell& shell, const SurfaceMesh& input, const std::string& what) {
  const sh::ShellVerification v = sh::verify_shell(shell, input);
  EXPECT_TRUE(v.positive()) << what;
  EXPECT_TRUE(v.separated()) << what << ": " << v.intersecting_input_faces << " crossing faces";
  EXPECT_TRUE(v.section()) << what << ": " << v.non_section_faces << " non-section faces";
  EXPECT_TRUE(v.embedded_reference()) << what << ": " << v.reference_self_intersections;
  EXPECT_EQ(v.roundtrip_failures, 0) << what;
  EXPECT_LT(v.roundtrip_max_error_rel, 1e-12) << what;
}

struct Coarse {
  sh::Shell coarse;
  sh::SimplifyStats stats;
};
Coarse coarsen(const SurfaceMesh& m, const std::vector<std::array<int, 2>>& features, bool chains,
               double eps_rel, bool full_recheck = false, bool grid = true) {
  const double unit = curvefem::bbox_longest_edge(m.V);
  sh::ShellStats build_stats;
  sh::ShellOptions so;
  so.max_thickness_per_edge = 1;
  const sh::Shell shell = sh::build_shell(m, so, build_stats);
  sh::SimplifyOptions o;
  o.max_distance = eps_rel * unit;
  o.max_mips = 10;
  o.zoom = 0.02 * unit;
  o.frozen_input_vertices.assign(m.num_vertices(), 0);
  for (const auto& e : features) o.frozen_input_vertices[e[0]] = o.frozen_input_vertices[e[1]] = 1;
  o.feature_edges = features;
  o.collapse_chains = chains;
  o.chain_full_recheck = full_recheck;
  o.chain_grid = grid;
  Coarse r;
  r.coarse = sh::simplify_shell(shell, m, o, r.stats);
  return r;
}

// Every input feature vertex is a coarse corner or inside exactly one coarse feature edge, whose
// ends are coarse corners joined by a coarse edge; snapped points lie within the bound.
void expect_chains_kept(const Coarse& r, const SurfaceMesh& m,
                        const std::vector<std::array<int, 2>>& features, double bound) {
  std::set<int> corners, feature_vertices;
  for (int v = 0; v < r.coarse.mid.rows(); ++v)
    if (r.coarse.input_vertex[v] >= 0) corners.insert(r.coarse.input_vertex[v]);
  std::set<std::pair<int, int>> coarse_edges;
  for (int f = 0; f < r.coarse.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = r.coarse.input_vertex[r.coarse.F(f, k)];
      const int b = r.coarse.input_vertex[r.coarse.F(f, (k + 1) % 3)];
      coarse_edges.insert({std::min(a, b), std::max(a, b)});
    }
  for (const auto& e : features) feature_vertices.insert({e[0], e[1]});
  std::set<int> snapped;
  for (const auto& q : r.coarse.reference) {
    EXPECT_TRUE(snapped.insert(q.vertex).second);
    EXPECT_TRUE(feature_vertices.count(q.vertex)) << q.vertex;
    EXPECT_FALSE(corners.count(q.vertex)) << q.vertex;
    EXPECT_TRUE(coarse_edges.count({std::min(q.a, q.b), std::max(q.a, q.b)}))
        << q.a << "-" << q.b << " is not a coarse edge";
    const Vector3d a = m.V.row(q.a), b = m.V.row(q.b), x = m.V.row(q.vertex);
    EXPECT_LE((x - (a + q.s * (b - a))).norm(), bound * (1 + 1e-12));
  }
  for (int x : feature_vertices) EXPECT_TRUE(corners.count(x) || snapped.count(x)) << x;
}

// Two coarsenings that must agree: the same chain collapses, shells, snaps and refusals.
void expect_same_coarsening(const Coarse& a, const Coarse& b) {
  EXPECT_EQ(a.stats.chain_collapses, b.stats.chain_collapses);
  EXPECT_EQ(a.coarse.F, b.coarse.F);
  EXPECT_EQ(a.coarse.mid, b.coarse.mid);
  EXPECT_EQ(a.coarse.base, b.coarse.base);
  EXPECT_EQ(a.coarse.top, b.coarse.top);
  ASSERT_EQ(a.coarse.reference.size(), b.coarse.reference.size());
  for (std::size_t i = 0; i < a.coarse.reference.size(); ++i) {
    EXPECT_EQ(a.coarse.reference[i].vertex, b.coarse.reference[i].vertex);
    EXPECT_EQ(a.coarse.reference[i].s, b.coarse.reference[i].s);
  }
  const auto& x = a.stats.collapse_rejections;
  const auto& y = b.stats.collapse_rejections;
  EXPECT_EQ(x.shape, y.shape);
  EXPECT_EQ(x.distance, y.distance);
  EXPECT_EQ(x.positivity, y.positivity);
  EXPECT_EQ(x.intersection, y.intersection);
  EXPECT_EQ(x.section, y.section);
  EXPECT_EQ(x.coverage, y.coverage);
}

}  // namespace

TEST(ShellChains, ABoxCoarsensAlongItsEdges) {
  const SurfaceMesh box = curvefem::make_box(Vector3d(0, 0, 0), Vector3d(1, 2, 1), 6);
  const auto features = sharp_edges(box, 60);
  ASSERT_EQ(features.size(), 4u * 6 + 8u * 6);  // 4 edges of 2 (12 steps), 8 of 1 (6 steps)
  const double eps = 0.01;
  const Coarse frozen = coarsen(box, features, false, eps);
  const Coarse chains = coarsen(box, features, true, eps);
  std::cout << "box: " << frozen.coarse.F.rows() << " faces frozen, " << chains.coarse.F.rows()
            << " with " << chains.stats.chain_collapses << " chain collapses\n";
  EXPECT_EQ(frozen.stats.chain_collapses, 0);
  EXPECT_GT(chains.stats.chain_collapses, 40);
  // Without chain collapses all 68 feature vertices stay (132 faces when written); with them
  // only the 8 corners, the fewest a box can have.
  EXPECT_GT(frozen.coarse.F.rows(), 100);
  EXPECT_EQ(chains.coarse.F.rows(), 12);
  expect_valid(frozen.coarse, box, "frozen");
  expect_valid(chains.coarse, box, "chains");
  expect_chains_kept(chains, box, features, eps * 2);
  EXPECT_GT(chains.stats.snapped_vertices, 40);
  EXPECT_LE(chains.stats.chain_max_distance, 1e-12);  // straight edges: snapped onto themselves
}

TEST(ShellChains, CircularRimsSnapOntoChordsWithinTheBound) {
  const SurfaceMesh cyl = curvefem::make_cylinder(48, 8, 4, 2.0);
  const auto features = sharp_edges(cyl, 60);
  ASSERT_EQ(features.size(), 96u);  // the two rims
  const double eps = 0.01, unit = curvefem::bbox_longest_edge(cyl.V);
  const Coarse frozen = coarsen(cyl, features, false, eps);
  const Coarse chains = coarsen(cyl, features, true, eps);
  std::cout << "cylinder: " << frozen.coarse.F.rows() << " faces frozen, " << chains.coarse.F.rows()
            << " with " << chains.stats.chain_collapses << " chain collapses, snapped "
            << chains.stats.snapped_vertices << ", max " << chains.stats.chain_max_distance / unit
            << " of bbox\n";
  EXPECT_GT(chains.stats.chain_collapses, 20);
  EXPECT_LT(chains.coarse.F.rows(), frozen.coarse.F.rows());
  expect_valid(chains.coarse, cyl, "chains");
  expect_chains_kept(chains, cyl, features, eps * unit);
  // The rims are curved: the snapped points leave the input, by up to the bound.
  EXPECT_GT(chains.stats.chain_max_distance, 0.2 * eps * unit);
  EXPECT_LE(chains.stats.chain_max_distance, eps * unit);
}

TEST(ShellChains, RecheckingOnlyTheSnappedFacesGivesTheFullChecksShell) {
  // A chain collapse re-checks the unchanged prisms near the faces it snaps against those faces
  // only; re-checking them in full must decide every collapse the same way.
  // A jagged rim (radius alternating by 1%) snaps far; a thin plate (0.02 thick, eps 0.01) has
  // its chains next to the other side's prisms.
  auto jag = [](SurfaceMesh m, double amplitude) {
    const double zmax = m.V.col(2).maxCoeff(), zmin = m.V.col(2).minCoeff();
    for (int v = 0, rim = 0; v < m.num_vertices(); ++v)
      if ((m.V(v, 2) == zmax || m.V(v, 2) == zmin) && std::hypot(m.V(v, 0), m.V(v, 1)) > 0.99)
        m.V.row(v).head<2>() *= (rim++ % 2 ? 1 + amplitude : 1 - amplitude);
    return m;
  };
  const SurfaceMesh jagged = jag(curvefem::make_cylinder(48, 8, 4, 2.0), 0.01);
  for (const auto& [name, mesh] :
       {std::pair{"cylinder", curvefem::make_cylinder(48, 8, 4, 2.0)},
        std::pair{"jagged cylinder", jagged},
        std::pair{"plate", curvefem::make_box(Vector3d(0, 0, 0), Vector3d(1, 1, 0.02), 12)},
        std::pair{"box", curvefem::make_box(Vector3d(0, 0, 0), Vector3d(1, 2, 1), 6)}}) {
    SCOPED_TRACE(name);
    const auto features = sharp_edges(mesh, 60);
    const Coarse fast = coarsen(mesh, features, true, 0.01);
    const Coarse full = coarsen(mesh, features, true, 0.01, true);
    EXPECT_GT(fast.stats.chain_collapses, 20);
    expect_same_coarsening(fast, full);
  }
}

TEST(ShellChains, TheGridOverThePrismsFindsThePrismsEveryBoxTestFinds) {
  // A chain collapse re-checks every live prism whose box meets a face it snaps; the grid over
  // the prisms' boxes must hand it the same prisms as testing every live prism's box.
  for (const auto& [name, mesh] :
       {std::pair{"cylinder", curvefem::make_cylinder(48, 8, 4, 2.0)},
        std::pair{"plate", curvefem::make_box(Vector3d(0, 0, 0), Vector3d(1, 1, 0.02), 12)},
        std::pair{"box", curvefem::make_box(Vector3d(0, 0, 0), Vector3d(1, 2, 1), 6)}}) {
    SCOPED_TRACE(name);
    const auto features = sharp_edges(mesh, 60);
    const Coarse grid = coarsen(mesh, features, true, 0.01);
    const Coarse scan = coarsen(mesh, features, true, 0.01, false, false);
    EXPECT_GT(grid.stats.chain_collapses, 20);
    // The scan tests every live prism; the grid far fewer.
    EXPECT_EQ(scan.stats.chain_prisms_tested, scan.stats.chain_prisms_live);
    EXPECT_EQ(grid.stats.chain_prisms_live, scan.stats.chain_prisms_live);
    EXPECT_LT(grid.stats.chain_prisms_tested, scan.stats.chain_prisms_live / 2);
    std::cout << name << ": prisms tested " << grid.stats.chain_prisms_tested << " of "
              << grid.stats.chain_prisms_live << "\n";
    expect_same_coarsening(grid, scan);
  }
}
