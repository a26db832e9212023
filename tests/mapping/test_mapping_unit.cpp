// mapping/ on tiny meshes built in code: point location on curved triangles, φ = identity,
// selections, and the exact transfer of a FE field to the input vertices.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "fem/space/function_space.hpp"
#include "mapping/boundary_inverse.hpp"
#include "mapping/selection.hpp"
#include "mapping/surface_transfer.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"

using namespace curvefem;
using namespace curvefem::mapping;

namespace {
/// The icosphere as order-k triangles with every node pushed onto the unit sphere.
LagrangeMesh curved_sphere_triangles(int level, int k) {
  const SurfaceMesh s = make_icosphere(level);
  const auto& lattice = lagrange_lattice(CellKind::triangle, k);
  LagrangeMesh t;
  t.kind = CellKind::triangle;
  t.order = k;
  t.cells.resize(s.num_faces(), Eigen::Index(lattice.size()));
  std::vector<Eigen::Vector3d> nodes;
  for (int f = 0; f < s.num_faces(); ++f)
    for (std::size_t n = 0; n < lattice.size(); ++n) {  // nodes duplicated per face: fine here
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      for (int j = 0; j < 3; ++j) p += lattice[n][j] * s.V.row(s.F(f, j)).transpose() / k;
      t.cells(f, Eigen::Index(n)) = int(nodes.size());
      nodes.push_back(p.normalized());
    }
  t.nodes.resize(Eigen::Index(nodes.size()), 3);
  for (std::size_t i = 0; i < nodes.size(); ++i) t.nodes.row(Eigen::Index(i)) = nodes[i];
  return t;
}

/// The dense pipeline's input for a tet mesh: its nodes (so the mesh's nodes are the input's
/// vertices; interior ones unreferenced, without an image) and its boundary faces.
SurfaceMesh boundary_as_input(const LagrangeMesh& mesh) {
  const fem::FunctionSpace space1 = fem::build_function_space(mesh, 1);
  SurfaceMesh input;
  input.V = mesh.nodes;
  input.F.resize(Eigen::Index(space1.boundary_faces.size()), 3);
  for (std::size_t f = 0; f < space1.boundary_faces.size(); ++f) {
    const auto [c, j] = space1.boundary_faces[f];
    int n = 0;
    for (int i = 0; i < 4; ++i)
      if (i != j) input.F(Eigen::Index(f), n++) = mesh.cells(c, i);
  }
  return input;
}
}  // namespace

TEST(TriangleLocator, InvertsCurvedTrianglesAndRejectsPointsOffTheSurface) {
  const LagrangeMesh t = curved_sphere_triangles(1, 3);
  const TriangleLocator locator(t);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  for (int i = 0; i < 200; ++i) {
    const int f = int(rng() % t.num_cells());
    double u = U(rng), v = U(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Eigen::Vector3d x = t.map(f, {u, v, 0});
    const auto p = locator.locate(x);
    ASSERT_TRUE(p.has_value()) << i;
    EXPECT_LT((t.map(p->face, {p->u, p->v, 0}) - x).norm(), 1e-12);
    if (p->face == f) {
      EXPECT_NEAR(std::abs(p->u - u) + std::abs(p->v - v), 0.0, 1e-10);
    }
  }
  EXPECT_FALSE(locator.locate(Eigen::Vector3d(0.3, 0.2, 0.1)).has_value());   // inside
  EXPECT_FALSE(locator.locate(Eigen::Vector3d(0.0, 0.0, 1.01)).has_value());  // outside
}

TEST(BoundaryInverse, IdentityReturnsThePointOnItsInputFace) {
  const SurfaceMesh box = make_box({0, 0, 0}, {1, 2, 3}, 3);
  const BoundaryInverse inv = BoundaryInverse::identity(box);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0, 1);
  for (int i = 0; i < 100; ++i) {
    const int f = int(rng() % box.num_faces());
    Eigen::Vector3d b(U(rng), U(rng), U(rng));
    b /= b.sum();
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    for (int j = 0; j < 3; ++j) x += b[j] * box.V.row(box.F(f, j)).transpose();
    const InputPoint p = inv.at(x);
    EXPECT_LT((p.position - x).norm(), 1e-14);
    // The face found lies in the same side plane (same tag) as the face the point came from.
    EXPECT_EQ(box.tags[p.face], box.tags[f]);
  }
  EXPECT_THROW(inv.at(Eigen::Vector3d(0.5, 1, 1.5)), MeshingError);
}

TEST(Selection, KindsAndCombinationsArePointwise) {
  const SurfaceMesh box = make_box({0, 0, 0}, {1, 1, 1}, 2);
  Selection plane{.kind = Selection::Kind::plane};
  plane.point = {0.5, 0, 0};
  plane.direction = {1, 0, 0};
  Selection cone{.kind = Selection::Kind::normal};
  cone.direction = {0, 0, 2};  // not normalized on purpose
  cone.angle_deg = 10;
  Selection tag{.kind = Selection::Kind::tag, .tag = 6};  // +z side
  Selection both{.kind = Selection::Kind::all_of, .children = {plane, cone}};
  Selection either{.kind = Selection::Kind::any_of, .children = {plane, cone}};
  Selection neither{.kind = Selection::Kind::none_of, .children = {either}};
  int checked = 0;
  for (int f = 0; f < box.num_faces(); ++f) {
    InputPoint p;
    p.face = f;
    p.bary = Eigen::Vector3d::Constant(1.0 / 3);
    for (int j = 0; j < 3; ++j) p.position += p.bary[j] * box.V.row(box.F(f, j)).transpose();
    const SelectionSite s = site_of(box, p);
    const bool top = box.tags[f] == 6, right = p.position.x() >= 0.5;
    EXPECT_EQ(selects(plane, s), right);
    EXPECT_EQ(selects(cone, s), top);
    EXPECT_EQ(selects(tag, s), top);
    EXPECT_EQ(selects(both, s), top && right);
    EXPECT_EQ(selects(either, s), top || right);
    EXPECT_EQ(selects(neither, s), !(top || right));
    ++checked;
  }
  EXPECT_EQ(checked, 48);
  // A face straddling the plane x = 0.25 is partly covered: 2 of its 4 samples or similar.
  Selection cut{.kind = Selection::Kind::plane};
  cut.point = {0.25, 0, 0};
  cut.direction = {1, 0, 0};
  int partial = 0;
  for (int f = 0; f < box.num_faces(); ++f) {
    const double c = face_coverage(cut, box, f);
    partial += c > 0 && c < 1;
  }
  EXPECT_GT(partial, 0);
  EXPECT_TRUE(uses_face_data(neither));
  EXPECT_FALSE(uses_face_data(plane));
}

TEST(Selection, OuterBoxPointsAreSelectedOnlyThroughOuterBox) {
  const Eigen::Vector3d lo(-2, -2, -2), hi(2, 2, 2);
  const double tol = 1e-9;
  EXPECT_EQ(box_side_of({-2, 0.3, 0.1}, lo, hi, tol), 0);
  EXPECT_EQ(box_side_of({2 - 1e-12, 0.3, 0.1}, lo, hi, tol), 1);
  EXPECT_EQ(box_side_of({0.5, 0.3, 2}, lo, hi, tol), 5);
  EXPECT_EQ(box_side_of({0.5, 0.3, 1.9}, lo, hi, tol), -1);
  EXPECT_EQ(box_side_of({-2, -2, 0}, lo, hi, tol), 0);  // an edge: the first side in index order

  Selection any_side{.kind = Selection::Kind::outer_box};
  Selection zmax{.kind = Selection::Kind::outer_box, .box_side = 5};
  Selection all{.kind = Selection::Kind::all};
  Selection tag{.kind = Selection::Kind::tag, .tag = 0};
  Selection cone{.kind = Selection::Kind::normal};
  cone.direction = {0, 0, 1};
  cone.angle_deg = 180;  // every normal
  Selection right{.kind = Selection::Kind::plane};
  right.direction = {1, 0, 0};  // x >= 0
  Selection right_of_box{.kind = Selection::Kind::all_of, .children = {any_side, right}};
  Selection not_tag{.kind = Selection::Kind::none_of, .children = {tag}};

  SelectionSite top;  // a point of the box's z max side, x > 0
  top.x = {1, 0, 2};
  top.box_side = 5;
  SelectionSite left = top;  // of the x min side
  left.x = {-2, 0, 0};
  left.box_side = 0;
  SelectionSite input;  // a point of the input surface with tag 0
  input.x = {1, 0, 0};
  input.tag = 0;
  input.normal = {1, 0, 0};

  EXPECT_TRUE(selects_point(any_side, top));
  EXPECT_TRUE(selects_point(any_side, left));
  EXPECT_FALSE(selects_point(any_side, input));
  EXPECT_TRUE(selects_point(zmax, top));
  EXPECT_FALSE(selects_point(zmax, left));
  // The input-surface kinds never reach the box, on their own or under not / or.
  for (const Selection* s : {&all, &tag, &cone, &right, &not_tag}) {
    EXPECT_FALSE(selects_point(*s, top));
    EXPECT_FALSE(selects_point(*s, left));
  }
  EXPECT_TRUE(selects_point(all, input));
  EXPECT_TRUE(selects_point(tag, input));
  EXPECT_TRUE(selects_point(cone, input));
  EXPECT_FALSE(selects_point(not_tag, input));
  // Once outer_box is in the tree, box and plane are tested at the box point.
  EXPECT_TRUE(selects_point(right_of_box, top));
  EXPECT_FALSE(selects_point(right_of_box, left));
  EXPECT_FALSE(selects_point(right_of_box, input));
  Selection box_or_not_tag{.kind = Selection::Kind::any_of, .children = {zmax, not_tag}};
  EXPECT_TRUE(selects_point(box_or_not_tag, left));  // not tag: no tag on the box
  EXPECT_TRUE(uses_outer_box(box_or_not_tag));
  EXPECT_FALSE(uses_outer_box(not_tag));
  EXPECT_STREQ(box_side_name(3), "ymax");
  EXPECT_STREQ(box_side_name(-1), "all");
}

TEST(SurfaceTransfer, LinearFieldIsExactAtEveryInputVertexOfTheDenseBaseline) {
  // Dense pipeline on the unit cube: volume nodes first = input vertices, φ = identity.
  const LagrangeMesh mesh = make_cube_tets(2);
  const SurfaceMesh input = boundary_as_input(mesh);  // the interior node: no image
  const BoundaryMap map = make_identity_boundary_map(input);
  const SurfaceSamples s = locate_input_vertices(mesh, map);
  const auto ell = [](const Eigen::Vector3d& x) {
    return 1.5 - 2 * x.x() + 0.5 * x.y() + 3 * x.z();
  };
  for (int p : {1, 3}) {
    const fem::FunctionSpace space = fem::build_function_space(mesh, p);
    Eigen::VectorXd u(space.num_dofs);
    for (int d = 0; d < space.num_dofs; ++d) u[d] = ell(space.dof_points.row(d).transpose());
    const Eigen::MatrixXd values = evaluate_on_surface(space, u, 1, s);
    int mapped = 0;
    for (int v = 0; v < input.num_vertices(); ++v) {
      if (map.vertex_face[v] < 0) {
        EXPECT_TRUE(std::isnan(values(v, 0)));
        continue;
      }
      ++mapped;
      EXPECT_NEAR(values(v, 0), ell(input.V.row(v).transpose()), 1e-12) << v;
    }
    EXPECT_EQ(mapped, 26);  // 3³ nodes, one interior
    const SurfaceErrors e = surface_errors(
        input, values, [&](const Eigen::Vector3d& x, double* out) { out[0] = ell(x); });
    EXPECT_LT(e.l2, 1e-12);
    EXPECT_EQ(e.vertices, 26);
    // A wrong exact solution gives a visible error.
    const SurfaceErrors off = surface_errors(
        input, values, [&](const Eigen::Vector3d& x, double* out) { out[0] = ell(x) + 1; });
    EXPECT_NEAR(off.l2, std::sqrt(6.0), 1e-12);  // area 6, error 1
  }
}

TEST(SurfaceTransfer, TheExtensionToTheTargetIsExactToFirstOrder) {
  // P2 on straight tets holds q(x) = |x|² exactly; continued from x by d, the extension is
  // q(x) + ∇q(x)·d = q(x + d) − |d|²: its error is exactly the second-order term, which tests
  // the gradient and its pull-back through the tet's Jacobian. Three components at once.
  const LagrangeMesh mesh = make_cube_tets(2);
  const SurfaceMesh input = boundary_as_input(mesh);
  const BoundaryMap map = make_identity_boundary_map(input);
  const SurfaceSamples s = locate_input_vertices(mesh, map);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  const auto q = [](const Eigen::Vector3d& x) { return x.squaredNorm(); };
  const auto ell = [](const Eigen::Vector3d& x) { return 1.5 - 2 * x.x() + 3 * x.z(); };
  Eigen::VectorXd u(3 * space.num_dofs);
  for (int d = 0; d < space.num_dofs; ++d) {
    const Eigen::Vector3d x = space.dof_points.row(d).transpose();
    u.segment<3>(3 * d) << q(x), ell(x), -2 * q(x);
  }
  Eigen::MatrixXd targets = input.V;
  for (int v = 0; v < input.num_vertices(); ++v)
    targets.row(v) += 0.01 * Eigen::RowVector3d(std::sin(v), std::cos(3.0 * v), 0.5);
  const Eigen::MatrixXd got = evaluate_on_surface_extended(mesh, space, u, 3, s, targets);
  int mapped = 0;
  for (int v = 0; v < input.num_vertices(); ++v) {
    if (map.vertex_face[v] < 0) {
      EXPECT_TRUE(std::isnan(got(v, 0)));
      continue;
    }
    ++mapped;
    const Eigen::Vector3d y = targets.row(v).transpose();
    const double d2 = (targets.row(v) - input.V.row(v)).squaredNorm();
    EXPECT_NEAR(got(v, 0), q(y) - d2, 1e-12) << v;
    EXPECT_NEAR(got(v, 1), ell(y), 1e-12) << v;
    EXPECT_NEAR(got(v, 2), -2 * (q(y) - d2), 1e-12) << v;
  }
  EXPECT_EQ(mapped, 26);
  // With the targets at the images it is the plain evaluation.
  const Eigen::MatrixXd at = evaluate_on_surface_extended(mesh, space, u, 3, s, input.V);
  const Eigen::MatrixXd plain = evaluate_on_surface(space, u, 3, s);
  for (int v = 0; v < input.num_vertices(); ++v)
    if (map.vertex_face[v] >= 0) EXPECT_LT((at.row(v) - plain.row(v)).norm(), 1e-13) << v;
}

TEST(TriangleLocator, FindsPointsOnAStronglyCurledTriangle) {
  // One order-3 triangle bent around a cylinder through about 340 degrees, a curl the boundary
  // of a coarse curved mesh can have on a thin part. From the centroid alone, Gauss-Newton can
  // stop at a local minimum on the triangle's border; every point of the triangle must still be
  // found (the locator restarts from corners and edge midpoints).
  const int k = 3;
  const auto& lattice = lagrange_lattice(CellKind::triangle, k);
  LagrangeMesh t;
  t.kind = CellKind::triangle;
  t.order = k;
  t.cells.resize(1, Eigen::Index(lattice.size()));
  t.nodes.resize(Eigen::Index(lattice.size()), 3);
  const double R = 0.25, L = 1.5;  // arc length L on radius R: 344 degrees
  for (std::size_t n = 0; n < lattice.size(); ++n) {
    const double u = double(lattice[n][1]) / k, v = double(lattice[n][2]) / k;
    const double s = L * (u + 0.5 * v), w = 0.8 * v;
    t.cells(0, Eigen::Index(n)) = int(n);
    t.nodes.row(Eigen::Index(n)) =
        Eigen::RowVector3d(R * std::sin(s / R), w, R * (1 - std::cos(s / R)));
  }
  const TriangleLocator locator(t);
  int tested = 0;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; i + j <= 40; ++j) {
      const double u = i / 40.0, v = j / 40.0;
      const Eigen::Vector3d x = t.map(0, {u, v, 0});
      const auto p = locator.locate(x);
      ASSERT_TRUE(p.has_value()) << "u " << u << " v " << v;
      EXPECT_LT((t.map(0, {p->u, p->v, 0}) - x).norm(), 1e-10) << "u " << u << " v " << v;
      ++tested;
    }
  EXPECT_EQ(tested, 861);
}
