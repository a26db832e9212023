// φ⁻¹ without the shell code (issue 23): the saved fibers of a coarse shell
// (meshing/core/shell_fibers.hpp, built by meshing/shell/fibers_of.hpp) evaluated by
// meshing/core/fiber_projection.hpp agree with the shell projection P_T(f, u, v) at h = 0 on
// curved meshes (sphere, torus, a box and a cylinder with feature chains — a reference copy —, the
// crater and a noisy sphere with pinch points), and boundary_map.json carries them bit for bit.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>

#include "mapping/boundary_inverse.hpp"
#include "meshing/core/adversarial.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/fiber_projection.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/curved/curved_mesher.hpp"
#include "meshing/curved/features.hpp"
#include "meshing/io/boundary_map_io.hpp"
#include "meshing/shell/fibers_of.hpp"
#include "meshing/shell/projection.hpp"
#include "tests/support/test_support.hpp"

using namespace curvefem;
namespace cv = curvefem::meshing::curved;
namespace sh = curvefem::meshing::shell;

namespace {

cv::CurvedMesh curved(const SurfaceMesh& input, int k, bool features, double eps) {
  cv::CurvedMeshOptions o;
  o.order = k;
  o.eps_rel = eps;
  o.threads = 1;
  if (features) o.feature_edges = cv::detect_feature_edges(input, 60);
  cv::CurvedMeshStats stats;
  return cv::build_curved_mesh(input, o, stats);
}

struct Agreement {
  int points = 0, same_face = 0, same_bits = 0, neighbour_face = 0;
  int both_missing = 0, presence_mismatch = 0, unrelated_face = 0;
  int random_points = 0, random_same_bits = 0;  // the uniformly random points alone
  double max_error_rel = 0;
};

bool share_vertex(const SurfaceMesh& m, int a, int b) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (m.F(a, i) == m.F(b, j)) return true;
  return false;
}

// P_T at (f, u, v, 0) by the shell projection and by the fibers, at random points of every prism,
// its corners, edge points, points within rounding of its corners, and the images of the input
// vertices (where φ⁻¹ is evaluated by `curvefem mesh`'s round trip).
Agreement compare(const cv::CurvedMesh& cm, const SurfaceMesh& input, int per_prism,
                  unsigned seed) {
  // A shell built on a refinement of the input (Shell::refinement: the mesher's shape and thin
  // refinements) projects onto the refined surface, with that surface's reference copy; its
  // crossing is taken to the input face that holds it the way the fibers report it.
  const auto& rf = cm.shell.refinement;
  SurfaceMesh surface = input;
  sh::Shell shell = cm.shell;
  if (!rf.empty()) {
    surface.V.resize(input.V.rows() + rf.points.rows(), 3);
    surface.V << input.V, rf.points;
    surface.F = rf.faces;
    surface.tags.resize(0);
    shell.reference = rf.reference;
  }
  const sh::ShellProjection exact(shell, surface);
  const FiberProjection fibers(sh::fibers_of(cm.shell, input), input);
  struct Crossing {
    int face;
    Eigen::Vector3d bary, position;
  };
  auto exact_project = [&](int f, double u, double v) -> std::optional<Crossing> {
    const auto e = exact.project(sh::PrismPoint{f, u, v, 0.0});
    if (!e) return std::nullopt;
    Crossing c{e->face, e->bary, e->position};
    if (!rf.empty()) {
      c.face = rf.parent[std::size_t(e->face)];
      c.bary.setZero();
      for (int k = 0; k < 3; ++k) c.bary += e->bary[k] * rf.bary[std::size_t(e->face)].col(k);
      c.position.setZero();
      for (int k = 0; k < 3; ++k)
        c.position += c.bary[k] * Eigen::Vector3d(input.V.row(input.F(c.face, k)));
    }
    return c;
  };
  const double unit = bbox_longest_edge(input.V);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  Agreement a;
  auto check = [&](int f, double u, double v, bool random = false) {
    ++a.points;
    a.random_points += random;
    const auto e = exact_project(f, u, v);
    const auto g = fibers.project(f, u, v);
    if (!e || !g) {
      if (!e && !g)
        ++a.both_missing;
      else
        ++a.presence_mismatch, ADD_FAILURE() << "prism " << f << " (" << u << ", " << v << ")";
      return;
    }
    const double error = (e->position - g->position).norm() / unit;
    a.max_error_rel = std::max(a.max_error_rel, error);
    if (e->face == g->face) {
      ++a.same_face;
      if (std::memcmp(e->position.data(), g->position.data(), sizeof(double) * 3) == 0 &&
          std::memcmp(e->bary.data(), g->bary.data(), sizeof(double) * 3) == 0) {
        ++a.same_bits;
        a.random_same_bits += random;
      }
    } else if (share_vertex(input, e->face, g->face)) {
      ++a.neighbour_face;
    } else {
      ++a.unrelated_face;
    }
  };
  const double tiny[] = {0.0, 1e-300, 1e-17, 1e-12, 1e-6};
  for (int f = 0; f < cm.shell.F.rows(); ++f) {
    for (int i = 0; i < per_prism; ++i) {
      double u = U(rng), v = U(rng);
      if (u + v > 1) u = 1 - u, v = 1 - v;
      check(f, u, v, true);
    }
    const double t = U(rng);
    for (const auto& [u, v] : {std::pair{0.0, 0.0},
                               {1.0, 0.0},
                               {0.0, 1.0},
                               {t, 0.0},
                               {0.0, t},
                               {t, 1 - t},
                               {1.0 / 3, 1.0 / 3}})
      check(f, u, v);
    for (double d : tiny) {
      check(f, d, d);
      check(f, 1 - 2 * d, d);
      check(f, d, 1 - 2 * d);
    }
  }
  for (int v = 0; v < cm.map.num_input_vertices(); ++v)
    if (cm.map.vertex_face[v] >= 0)
      check(cm.map.vertex_face[v], cm.map.vertex_uv(v, 0), cm.map.vertex_uv(v, 1));
  return a;
}

void expect_agreement(const char* name, const Agreement& a, const cv::CurvedMesh& cm) {
  std::printf(
      "%s: %d prisms, %d points, max |P_T - fibers| = %.3g (rel), same face %d (bitwise %d), "
      "neighbour face %d, both missing %d; random points %d, bitwise %d\n",
      name, int(cm.shell.F.rows()), a.points, a.max_error_rel, a.same_face, a.same_bits,
      a.neighbour_face, a.both_missing, a.random_points, a.random_same_bits);
  EXPECT_EQ(a.presence_mismatch, 0) << name;
  EXPECT_EQ(a.unrelated_face, 0) << name;
  EXPECT_LE(a.max_error_rel, 1e-12) << name;
  EXPECT_EQ(a.both_missing, 0) << name;  // every fiber of a section crosses the input
  // A random point's fiber crosses the inside of one input face. Both searches decide with exact
  // predicates and solve with the same operations, so they give the same bits (corners, edges
  // and the input vertices' images are on input edges and vertices, where they may pick
  // different faces sharing the point).
  EXPECT_EQ(a.random_same_bits, a.random_points) << name;
}

}  // namespace

TEST(FiberProjection, AgreesWithTheShellProjectionOnASphere) {
  const SurfaceMesh input = make_icosphere(3);
  const cv::CurvedMesh cm = curved(input, 2, false, 0.02);
  ASSERT_LT(cm.shell.F.rows(), input.num_faces());  // coarsened: fibers cross many input faces
  expect_agreement("sphere", compare(cm, input, 40, 1), cm);
}

TEST(FiberProjection, AgreesWithTheShellProjectionOnATorus) {
  const SurfaceMesh input = make_torus(1.0, 0.35, 48, 16);
  const cv::CurvedMesh cm = curved(input, 2, false, 0.01);
  ASSERT_LT(cm.shell.F.rows(), input.num_faces());
  expect_agreement("torus", compare(cm, input, 40, 2), cm);
}

TEST(FiberProjection, AgreesWithTheShellProjectionThroughTheReferenceCopyOfFeatureChains) {
  // Input vertices inside coarse feature edges are snapped onto them: the fibers cross the
  // reference copy, and its crossings stand for input points with the same barycentrics. On the
  // box the snapped points round to the input's; on the cylinder's rims (curved chains cut by
  // straight coarse edges) they move off the input.
  const SurfaceMesh box = make_box({0, 0, 0}, {1, 2, 1}, 4);
  const cv::CurvedMesh cb = curved(box, 2, true, 0.01);
  ASSERT_EQ(cb.shell.reference.size(), 36u);  // 12 edges of 4 steps
  EXPECT_EQ(sh::fibers_of(cb.shell, box).reference_vertices.size(), 36u);
  expect_agreement("feature box", compare(cb, box, 60, 3), cb);

  const SurfaceMesh cylinder = make_cylinder(32, 4, 3, 1.0);
  const cv::CurvedMesh cc = curved(cylinder, 2, true, 0.01);
  const ShellFibers f = sh::fibers_of(cc.shell, cylinder);
  ASSERT_EQ(f.reference_vertices.size(), cc.shell.reference.size());
  int moved = 0;
  double furthest = 0;
  for (std::size_t i = 0; i < f.reference_vertices.size(); ++i) {
    const Eigen::Vector3d d =
        f.reference_positions.row(Eigen::Index(i)) - cylinder.V.row(f.reference_vertices[i]);
    moved += d.norm() > 0;
    furthest = std::max(furthest, d.norm());
  }
  std::printf("feature cylinder: %d of %zu reference vertices off the input, up to %.3g\n", moved,
              f.reference_vertices.size(), furthest);
  EXPECT_GT(moved, 0);
  expect_agreement("feature cylinder", compare(cc, cylinder, 40, 6), cc);
}

TEST(FiberProjection, AgreesWithTheShellProjectionAtPinchPoints) {
  // The crater's rim vertices 0 and 5 are pinch points of the coarse shell too.
  const SurfaceMesh crater = test::crater_mesh();
  const cv::CurvedMesh cm = curved(crater, 2, false, 0.01);
  int pinches = 0;
  const ShellFibers f = sh::fibers_of(cm.shell, crater);
  for (int v = 0; v < f.num_vertices(); ++v) pinches += f.pinched(v);
  EXPECT_EQ(pinches, 2);
  expect_agreement("crater", compare(cm, crater, 400, 4), cm);
}

TEST(FiberProjection, AgreesWithTheShellProjectionOnANoisySphere) {
  // Radial noise of 20 edge lengths on a level-2 icosphere (noise_sphere_20 is level 3): folds
  // and singular vertices, pinch points of the coarse shell.
  const SurfaceMesh noisy = make_radial_noise_sphere(2, 20.0, 1.0, 13);
  const cv::CurvedMesh cn = curved(noisy, 2, true, 0.01);
  const ShellFibers fn = sh::fibers_of(cn.shell, noisy);
  int pinches = 0;
  for (int v = 0; v < fn.num_vertices(); ++v) pinches += fn.pinched(v);
  std::printf("noise sphere: %d pinch points, %zu reference vertices\n", pinches,
              fn.reference_vertices.size());
  EXPECT_GT(pinches, 0);
  expect_agreement("noise sphere", compare(cn, noisy, 20, 5), cn);
}

namespace {

template <class M>
bool same_bits(const M& a, const M& b) {
  if (a.size() == 0 && b.size() == 0) return true;  // 0 × 3 and 0 × 0 hold the same nothing
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(typename M::Scalar) * std::size_t(a.size())) == 0;
}

}  // namespace

namespace {

// Writes the map and fibers of a curved mesh, reads them back, and compares bit for bit; then φ⁻¹
// from the file against φ⁻¹ from memory at every input vertex's image and 500 random points of
// the curved boundary. Returns the number of points compared.
int round_trip(const char* name, const SurfaceMesh& input, const cv::CurvedMeshOptions& o) {
  cv::CurvedMeshStats stats;
  const cv::CurvedMesh cm = cv::build_curved_mesh(input, o, stats);
  const ShellFibers fibers = sh::fibers_of(cm.shell, input);
  const auto dir = test::scratch_dir(std::string("boundary_map_file_") + name);
  io::write_boundary_map(dir / "boundary_map.json", cm.map, "/some/input.obj", &fibers);
  const io::SavedBoundaryMap saved = io::read_boundary_map(dir / "boundary_map.json");
  EXPECT_EQ(saved.input, "/some/input.obj");
  const BoundaryMap& m = saved.map;
  EXPECT_EQ(m.boundary.order, o.order);
  EXPECT_TRUE(same_bits(m.boundary.nodes, cm.map.boundary.nodes));
  EXPECT_TRUE(same_bits(m.boundary.cells, cm.map.boundary.cells));
  EXPECT_TRUE(same_bits(m.boundary_node_to_volume, cm.map.boundary_node_to_volume));
  EXPECT_TRUE(same_bits(m.vertex_face, cm.map.vertex_face));
  EXPECT_TRUE(same_bits(m.vertex_uv, cm.map.vertex_uv));
  EXPECT_TRUE(same_bits(m.point_input_face, cm.map.point_input_face));
  EXPECT_TRUE(same_bits(m.point_bary, cm.map.point_bary));
  EXPECT_TRUE(same_bits(m.point_face, cm.map.point_face));
  EXPECT_TRUE(same_bits(m.point_uv, cm.map.point_uv));
  EXPECT_EQ(m.feature_edges, cm.map.feature_edges);
  EXPECT_EQ(m.eps_scale, cm.map.eps_scale);
  EXPECT_EQ(m.eps_scale.size(), o.eps_scale.size());
  EXPECT_TRUE(saved.fibers.has_value());
  if (!saved.fibers) return 0;
  EXPECT_TRUE(identical(*saved.fibers, fibers));

  const mapping::BoundaryInverse from_memory(cm.map, fibers, input);
  const mapping::BoundaryInverse from_file(m, *saved.fibers, input);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<Eigen::Vector3d> points;
  for (int v = 0; v < input.num_vertices(); ++v) points.push_back(cm.map.image(v));
  for (int i = 0; i < 500; ++i) {
    double u = U(rng), v = U(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    points.push_back(
        cm.map.boundary.map(int(rng() % cm.map.boundary.num_cells()), Eigen::Vector3d(u, v, 0)));
  }
  int compared = 0;
  for (const Eigen::Vector3d& x : points) {
    const auto a = from_memory(x), b = from_file(x);
    EXPECT_TRUE(a.has_value() && b.has_value()) << name;
    if (!a || !b) continue;
    ++compared;
    EXPECT_EQ(a->face, b->face);
    EXPECT_EQ(std::memcmp(a->bary.data(), b->bary.data(), sizeof(double) * 3), 0);
    EXPECT_EQ(std::memcmp(a->position.data(), b->position.data(), sizeof(double) * 3), 0);
  }
  std::printf(
      "%s: %d input faces, %d prisms, %.1f candidate faces per prism, %zu reference vertices, %d "
      "distance points, %ju bytes; phi^-1 compared at %d points\n",
      name, input.num_faces(), fibers.num_prisms(),
      double(fibers.candidate_faces.size()) / fibers.num_prisms(), fibers.reference_vertices.size(),
      cm.map.num_points(), std::uintmax_t(std::filesystem::file_size(dir / "boundary_map.json")),
      compared);
  return compared;
}

}  // namespace

TEST(BoundaryMapFile, RoundTripsTheMapAndFibersBitForBitAndPhiInverseExactly) {
  cv::CurvedMeshOptions o;
  o.order = 3;
  o.eps_rel = 0.01;
  o.threads = 1;
  // Feature chains (a reference copy off the input).
  const SurfaceMesh cylinder = make_cylinder(32, 4, 3, 1.0);
  o.feature_edges = cv::detect_feature_edges(cylinder, 60);
  EXPECT_EQ(round_trip("cylinder", cylinder, o), cylinder.num_vertices() + 500);
  // A shell built on the shape-refined input (needle sides, feature edges bisected): the fibers
  // carry the refined surface (ShellFibers::surface_*), written and read back bit for bit.
  const SurfaceMesh bar = make_adversarial("box_thin_long");
  o.feature_edges = cv::detect_feature_edges(bar, 60);
  ASSERT_GT(o.shape_refine, 0);
  {
    cv::CurvedMeshStats stats;
    const cv::CurvedMesh cm = cv::build_curved_mesh(bar, o, stats);
    ASSERT_GT(stats.shape_feature_splits, 0);
    ASSERT_TRUE(sh::fibers_of(cm.shell, bar).refined());
  }
  EXPECT_EQ(round_trip("bar", bar, o), bar.num_vertices() + 500);
  // Distance points, and a spatially varying ε (half of it where z > 0).
  const SurfaceMesh sphere = make_icosphere(2);
  o.feature_edges.clear();
  o.eps_samples = 2;
  for (int v = 0; v < sphere.num_vertices(); ++v)
    o.eps_scale.push_back(sphere.V(v, 2) > 0 ? 0.5 : 1.0);
  EXPECT_EQ(round_trip("sphere", sphere, o), sphere.num_vertices() + 500);
}

TEST(BoundaryMapFile, AVersionOneFileWithTheShellAsksToRemesh) {
  const auto dir = test::scratch_dir("boundary_map_v1");
  const auto path = dir / "boundary_map.json";
  {
    std::ofstream(path) << R"({"format": "curvefem-boundary-map", "version": 1, "input": "x.obj",
      "order": 1, "input_vertices": 0, "boundary": {"nodes": [], "triangles": [],
      "volume_node": []}, "vertex_face": [], "vertex_uv": [],
      "shell": {"base": [], "mid": [], "top": [], "faces": [], "singular": [],
      "input_vertex": [], "face_parent": []}})";
  }
  try {
    io::read_boundary_map(path);
    FAIL() << "a version-1 map with a shell was read";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find("re-run `curvefem mesh`"), std::string::npos) << what;
  }
  // A fibers block that does not fit the boundary: named.
  {
    std::ofstream(path) << R"({"format": "curvefem-boundary-map", "version": 2, "input": "x.obj",
      "order": 1, "input_vertices": 0, "boundary": {"nodes": [], "triangles": [],
      "volume_node": []}, "vertex_face": [], "vertex_uv": [],
      "fibers": {"base": [[0,0,0],[1,0,0],[0,1,0]], "mid": [[0,0,0],[1,0,0],[0,1,0]],
      "top": [[0,0,0],[1,0,0],[0,1,0]], "faces": [[0,1,2]], "candidates": [[0]]}})";
  }
  EXPECT_THROW(io::read_boundary_map(path), InputError);
}
