// φ⁻¹ on saved shell fibers with mapping/ and meshing/core alone: this executable links
// curvefem_mapping only (no curvefem_shell, no curvefem_curved; tests/mapping/CMakeLists.txt also
// refuses a direct link of curvefem_mapping to them), on shells built by hand around an
// octahedron.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "mapping/boundary_inverse.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/fiber_projection.hpp"
#include "meshing/core/prism_split.hpp"
#include "tests/support/test_support.hpp"

using namespace curvefem;

namespace {

SurfaceMesh octahedron(double scale = 1.0) {
  SurfaceMesh m;
  m.V.resize(6, 3);
  m.V << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  m.V *= scale;
  m.F.resize(8, 3);
  m.F << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  return m;
}

// Prisms on the unit octahedron: base 0.8 V, mid V, top 1.25 V (a pinched vertex keeps all three
// at V); every input face a candidate of every prism.
ShellFibers octahedron_fibers(int pinched = -1) {
  const SurfaceMesh o = octahedron();
  ShellFibers s;
  s.mid = o.V;
  s.base = 0.8 * o.V;
  s.top = 1.25 * o.V;
  if (pinched >= 0) s.base.row(pinched) = s.top.row(pinched) = s.mid.row(pinched);
  s.faces.resize(8, 3);
  for (int f = 0; f < 8; ++f) {
    const Eigen::Vector3i F = o.F.row(f);
    const int r = min_rotation(F);
    for (int c = 0; c < 3; ++c) s.faces(f, c) = F[(r + c) % 3];
  }
  s.candidate_offsets.push_back(0);
  for (int f = 0; f < 8; ++f) {
    for (int t = 0; t < 8; ++t) s.candidate_faces.push_back(t);
    s.candidate_offsets.push_back(int(s.candidate_faces.size()));
  }
  return s;
}

Eigen::Vector3d corner(const ShellFibers& s, int f, double u, double v) {
  return (1 - u - v) * Eigen::Vector3d(s.mid.row(s.faces(f, 0))) +
         u * Eigen::Vector3d(s.mid.row(s.faces(f, 1))) +
         v * Eigen::Vector3d(s.mid.row(s.faces(f, 2)));
}

}  // namespace

TEST(FiberProjectionUnit, OnTheMiddleSurfaceTheFiberCrossesAtItsOwnPoint) {
  const SurfaceMesh input = octahedron();
  ASSERT_GT(signed_volume(input), 0);
  const FiberProjection p(octahedron_fibers(), input);
  for (int f = 0; f < 8; ++f)
    for (const auto& [u, v] : {std::pair{0.2, 0.3}, {0.6, 0.1}, {1.0 / 3, 1.0 / 3}}) {
      const auto x = p.project(f, u, v);
      ASSERT_TRUE(x.has_value());
      EXPECT_EQ(x->face, f);  // the middle triangle is input face f itself
      EXPECT_LT((x->position - corner(p.fibers(), f, u, v)).norm(), 1e-15);
      EXPECT_NEAR(x->bary.sum(), 1.0, 1e-15);
      EXPECT_GE(x->bary.minCoeff(), -1e-15);
    }
  EXPECT_FALSE(p.project(8, 0.2, 0.2).has_value());
  EXPECT_FALSE(p.project(-1, 0.2, 0.2).has_value());
}

TEST(FiberProjectionUnit, AnOffsetInputIsCrossedOnItsPlaneAndPillarsHitItsVertices) {
  // The input is the octahedron scaled by 1.1: between the middle (1) and the top (1.25).
  const SurfaceMesh input = octahedron(1.1);
  const FiberProjection p(octahedron_fibers(), input);
  for (int f = 0; f < 8; ++f) {
    for (const auto& [u, v] : {std::pair{0.2, 0.3}, {0.6, 0.1}, {0.05, 0.9}}) {
      const auto x = p.project(f, u, v);
      ASSERT_TRUE(x.has_value());
      // On the plane |x| + |y| + |z| = 1.1 of the face with the same vertices.
      EXPECT_NEAR(x->position.cwiseAbs().sum(), 1.1, 1e-14);
      EXPECT_GE(x->bary.minCoeff(), -1e-14);
      Eigen::Vector3d from_bary = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k)
        from_bary += x->bary[k] * input.V.row(input.F(x->face, k)).transpose();
      EXPECT_LT((from_bary - x->position).norm(), 1e-15);
    }
    // At a corner the fiber is the pillar 0.8 V .. 1.25 V: it crosses at the input vertex.
    for (int c = 0; c < 3; ++c) {
      const auto x = p.project(f, c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0);
      ASSERT_TRUE(x.has_value());
      EXPECT_LT((x->position - input.V.row(p.fibers().faces(f, c)).transpose()).norm(), 1e-15);
    }
  }
}

TEST(FiberProjectionUnit, PinchPointsMapToThemselvesAndFibersNearThemStayOnTheInput) {
  // Vertex 4 (0, 0, 1) is pinched and shared by the input; the other input vertices sit at 1.1.
  SurfaceMesh input = octahedron(1.1);
  input.V.row(4) << 0, 0, 1;
  const FiberProjection p(octahedron_fibers(4), input);
  ASSERT_TRUE(p.fibers().pinched(4));
  for (int f = 0; f < 4; ++f) {  // the faces around vertex 4
    int s = 0;
    while (p.fibers().faces(f, s) != 4) ++s;
    auto uv = [&](double ws) {
      // weights: ws at corner s, the rest split evenly
      double w[3] = {(1 - ws) / 2, (1 - ws) / 2, (1 - ws) / 2};
      w[s] = ws;
      return std::pair{w[1], w[2]};
    };
    const auto [u0, v0] = uv(1.0);
    const auto at = p.project(f, u0, v0);
    ASSERT_TRUE(at.has_value());
    EXPECT_EQ(at->position, Eigen::Vector3d(0, 0, 1));  // exactly the pinch point
    EXPECT_EQ(at->bary.maxCoeff(), 1.0);
    for (double d : {1e-300, 1e-17, 1e-13, 1e-8, 1e-3}) {
      const auto [u, v] = uv(1 - d);
      const auto x = p.project(f, u, v);
      ASSERT_TRUE(x.has_value()) << "face " << f << ", 1 - w_s = " << d;
      EXPECT_LT((x->position - Eigen::Vector3d(0, 0, 1)).norm(), 2 * d + 1e-15) << d;
      // On the input face whose vertices are those of prism f.
      EXPECT_GE(x->bary.minCoeff(), -1e-12) << d;
      EXPECT_LE(x->position.cwiseAbs().sum(), 1.1 + 1e-14) << d;
      EXPECT_GE(x->position.cwiseAbs().sum(), 1.0 - 1e-14) << d;
    }
  }
}

TEST(FiberProjectionUnit, BoundaryInverseRunsOnFibersWithoutTheShellCode) {
  const SurfaceMesh input = octahedron(1.1);
  const ShellFibers fibers = octahedron_fibers();
  // The boundary of a straight mesh on the middle surface: triangle f = prism f's face.
  BoundaryMap map;
  map.boundary.kind = CellKind::triangle;
  map.boundary.order = 1;
  map.boundary.nodes = fibers.mid;
  map.boundary.cells = fibers.faces;
  map.boundary_node_to_volume = Eigen::VectorXi::LinSpaced(6, 0, 5);
  map.vertex_face = Eigen::VectorXi::Constant(6, -1);
  map.vertex_uv = Eigen::MatrixXd::Zero(6, 2);
  const mapping::BoundaryInverse inverse(map, fibers, input);
  const FiberProjection direct(fibers, input);
  for (int f = 0; f < 8; ++f) {
    const Eigen::Vector3d x = corner(fibers, f, 0.25, 0.35);
    const auto back = inverse(x);
    ASSERT_TRUE(back.has_value());
    const auto b = inverse.locate(x);
    ASSERT_TRUE(b.has_value());
    const auto expected = direct.project(b->face, b->u, b->v);
    ASSERT_TRUE(expected.has_value());
    EXPECT_EQ(back->position, expected->position);
    EXPECT_NEAR(back->position.cwiseAbs().sum(), 1.1, 1e-14);
  }
  // Fibers that do not fit: a prism count unlike the boundary's, a face the input lacks.
  ShellFibers fewer = fibers;
  fewer.faces.conservativeResize(7, 3);
  fewer.candidate_offsets.pop_back();
  fewer.candidate_faces.resize(std::size_t(fewer.candidate_offsets.back()));
  EXPECT_THROW(mapping::BoundaryInverse(map, fewer, input), InputError);
  ShellFibers beyond = fibers;
  beyond.candidate_faces[3] = 8;
  EXPECT_THROW(FiberProjection(beyond, input), InputError);
  ShellFibers unrotated = fibers;
  unrotated.faces.row(0) =
      Eigen::Vector3i(fibers.faces(0, 1), fibers.faces(0, 2), fibers.faces(0, 0));
  EXPECT_THROW(validate_structure(unrotated), InputError);
}

TEST(MappingLayering, NoFileOfMappingIncludesTheShellTheCurvedMesherOrTools) {
  const std::regex forbidden(R"(#\s*include\s*"(meshing/shell|meshing/curved|tools)/)");
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(test::source_dir() / "mapping")) {
    if (!e.is_regular_file()) continue;
    ++files;
    std::ifstream in(e.path());
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      EXPECT_FALSE(std::regex_search(line, forbidden))
          << e.path().string() << ":" << n << ": " << line;
    }
  }
  EXPECT_GE(files, 6);
}
