// meshing/param building blocks on tiny generated inputs: the symmetric Dirichlet energy and SLIM
// weights, chart cutting (and its InputErrors), Tutte's embedding, and the independent checker
// on hand-made flips, overlaps and nesting (it must be able to fail).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "meshing/core/error.hpp"
#include "meshing/param/cut_mesh.hpp"
#include "meshing/param/symmetric_dirichlet.hpp"
#include "meshing/param/tutte.hpp"
#include "meshing/param/uv_check.hpp"
#include "tests/meshing/param/param_inputs.hpp"

using namespace curvefem;
using namespace curvefem::meshing::param;

TEST(ParamEnergy, SymmetricDirichletValues) {
  const double a = 0.3;
  Eigen::Matrix2d R;
  R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  EXPECT_NEAR(symmetric_dirichlet(R), 4.0, 1e-14);
  EXPECT_NEAR(symmetric_dirichlet(2.0 * R), 2 * (4 + 0.25), 1e-13);
  Eigen::Matrix2d flip;
  flip << 1, 0, 0, -1;
  EXPECT_TRUE(std::isinf(symmetric_dirichlet(flip)));
  Eigen::Matrix2d J;
  J << 1.3, 0.4, -0.2, 0.7;
  const Eigen::Vector2d s = singular_values(J);
  EXPECT_NEAR(s[0] * s[1], J.determinant(), 1e-14);
  EXPECT_NEAR(s.squaredNorm(), J.squaredNorm(), 1e-14);
  // SLIM weights: the proxy's gradient 2 Wᵀ W (J − R) equals ∂D/∂J.
  Eigen::Matrix2d W, Rot;
  slim_weights(J, W, Rot);
  EXPECT_NEAR((2 * W.transpose() * W * (J - Rot) - symmetric_dirichlet_gradient(J)).norm(), 0,
              1e-12);
  // the gradient against a central difference
  Eigen::Matrix2d dJ;
  dJ << 0.1, -0.3, 0.2, 0.05;
  const double h = 1e-6;
  const double fd = (symmetric_dirichlet(J + h * dJ) - symmetric_dirichlet(J - h * dJ)) / (2 * h);
  EXPECT_NEAR(symmetric_dirichlet_gradient(J).cwiseProduct(dJ).sum(), fd, 1e-7);
}

// The Hessian of the Newton phase: against central differences of the gradient, symmetric, and
// its projection positive semi-definite, equal to it where it is already (near a rotation), and
// different where it is not (a strongly stretched J, where D is not convex in J).
TEST(ParamEnergy, SymmetricDirichletHessian) {
  auto vec = [](const Eigen::Matrix2d& M) {
    return Eigen::Vector4d(M(0, 0), M(0, 1), M(1, 0), M(1, 1));
  };
  int indefinite = 0;
  for (const Eigen::Matrix2d& J :
       {Eigen::Matrix2d{{1.3, 0.4}, {-0.2, 0.7}}, Eigen::Matrix2d{{1.02, 0.01}, {-0.03, 0.99}},
        Eigen::Matrix2d{{6.0, 0.5}, {0.3, 0.2}}, Eigen::Matrix2d{{0.1, -0.05}, {0.02, 0.15}}}) {
    const Eigen::Matrix4d H = symmetric_dirichlet_hessian(J, false);
    EXPECT_NEAR((H - H.transpose()).norm(), 0, 1e-12 * H.norm());
    const double h = 1e-6 * J.norm();
    for (int i = 0; i < 4; ++i) {
      Eigen::Matrix2d dJ = Eigen::Matrix2d::Zero();
      dJ(i / 2, i % 2) = h;
      const Eigen::Vector4d fd =
          (vec(symmetric_dirichlet_gradient(J + dJ)) - vec(symmetric_dirichlet_gradient(J - dJ))) /
          (2 * h);
      EXPECT_LT((H.col(i) - fd).norm(), 1e-6 * H.norm()) << "column " << i << " of\n" << J;
    }
    const Eigen::Matrix4d P = symmetric_dirichlet_hessian(J, true);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eh(H), ep(P);
    EXPECT_GE(ep.eigenvalues().minCoeff(), -1e-12 * H.norm());
    if (eh.eigenvalues().minCoeff() > 0) {
      EXPECT_NEAR((P - H).norm(), 0, 1e-10 * H.norm());
    } else {
      ++indefinite;
      EXPECT_GT((P - H).norm(), 1e-6 * H.norm());
    }
  }
  EXPECT_GE(indefinite, 1);  // the stretched J: the projection is exercised
  // At a rotation D's Hessian is 8 in the stretch directions and 0 along the rotation.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> at_identity(
      symmetric_dirichlet_hessian(Eigen::Matrix2d::Identity(), false));
  EXPECT_NEAR(at_identity.eigenvalues()[0], 0.0, 1e-12);
  EXPECT_NEAR(at_identity.eigenvalues()[3], 8.0, 1e-12);
}

TEST(ParamCut, TorusNeedsSeamsAndBadSeamsAreRejected) {
  auto [torus, seams] = test::cut_torus(2, 0.7, 24, 12);
  try {
    cut_into_charts(torus, {});
    FAIL() << "an uncut torus is not a disk";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("chart 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Euler characteristic 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0 boundary loop"), std::string::npos) << e.what();
  }
  // one seam loop only: an annulus (χ = 0, 2 boundary loops)
  std::vector<std::array<int, 2>> meridian(seams.begin(), seams.begin() + 12);
  try {
    cut_into_charts(torus, meridian);
    FAIL() << "a torus cut along one loop is an annulus";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 boundary loop"), std::string::npos) << e.what();
  }
  EXPECT_THROW(cut_into_charts(torus, {{0, 100}}), InputError);  // not an edge
  const CutMesh cut = cut_into_charts(torus, seams);
  EXPECT_EQ(cut.num_charts, 1);
  // the seam vertices are split: 24 × 12 vertices, + 24 + 12 copies along the loops, + 1 corner
  EXPECT_EQ(cut.num_uv_vertices(), 24 * 12 + 24 + 12 + 1);
  EXPECT_EQ(cut.boundary_loops[0].size(), std::size_t(2 * (24 + 12)));
}

TEST(ParamCut, GroupsAreCharts) {
  SurfaceMesh grid = test::bump_disk(6, 24, 0.2, 0.5);
  grid.tags.resize(grid.num_faces());
  for (int f = 0; f < grid.num_faces(); ++f) {
    const Eigen::Vector3d c =
        (grid.V.row(grid.F(f, 0)) + grid.V.row(grid.F(f, 1)) + grid.V.row(grid.F(f, 2))) / 3;
    grid.tags[f] = c.x() > 0 ? 1 : 2;
  }
  grid.tag_names = {{1, "east"}, {2, "west"}};
  const CutMesh cut = cut_into_charts(grid, {});
  EXPECT_EQ(cut.num_charts, 2);
  EXPECT_NE(cut.chart_names[0].find("east"), std::string::npos);
  CutOptions whole;
  whole.split_groups = false;
  EXPECT_EQ(cut_into_charts(grid, {}, whole).num_charts, 1);
}

TEST(ParamTutte, EmbeddingHasNoFlipAndMatchesArea) {
  const SurfaceMesh disk = test::bump_disk(10, 40, 1.5, 0.3);
  const CutMesh cut = cut_into_charts(disk, {});
  for (TutteWeights w : {TutteWeights::uniform, TutteWeights::mean_value}) {
    const Eigen::MatrixXd uv = tutte_layout(cut, w);
    const UvCheck c = check_uv_map(uv, cut.F);
    EXPECT_TRUE(c.bijective());
    const RestShapes rest = rest_shapes(cut);
    EXPECT_NEAR(c.triangle_area, rest.area.sum(), 1e-9 * rest.area.sum());
  }
}

// The verifier must see what it claims to see: a flipped triangle, crossing boundaries, a chart
// inside another, and two charts touching at a point.
TEST(ParamCheck, DetectsFlipsOverlapsAndNesting) {
  Eigen::MatrixXd uv(6, 2);
  uv << 0, 0, 4, 0, 0, 4, 1, 1, 2, 1, 1, 2;
  Eigen::MatrixXi F(2, 3);
  F << 0, 1, 2, 3, 4, 5;
  UvCheck c = check_uv_map(uv, F);  // small triangle inside the big one
  EXPECT_EQ(c.flips, 0);
  EXPECT_EQ(c.overlaps, 0);
  EXPECT_EQ(c.nested_charts, 1);
  EXPECT_FALSE(c.bijective());
  uv.row(4) << 5, 1;  // now its edges cross the big triangle's hypotenuse
  c = check_uv_map(uv, F);
  EXPECT_GE(c.overlaps, 2);
  uv.bottomRows(3) << 4, 0, 8, 0, 4, 4;  // touching at the point (4, 0) only: 2 × 2 edge pairs
  c = check_uv_map(uv, F);
  EXPECT_EQ(c.overlaps, 4);
  uv.bottomRows(3) << 5, 0, 8, 0, 5, 4;  // separate
  c = check_uv_map(uv, F);
  EXPECT_TRUE(c.bijective());
  F.row(1) << 3, 5, 4;  // clockwise
  c = check_uv_map(uv, F);
  EXPECT_EQ(c.flips, 1);
  // a fold: a disk of two triangles whose second one is folded back into the first; its boundary
  // (0, 0) (2, 0) (1, 0.5) (0, 2) is still a simple polygon: only the flip test sees it
  Eigen::MatrixXd fold(4, 2);
  fold << 0, 0, 2, 0, 0, 2, 1, 0.5;
  Eigen::MatrixXi G(2, 3);
  G << 0, 1, 2, 1, 3, 2;
  c = check_uv_map(fold, G);
  EXPECT_EQ(c.flips, 1);
  EXPECT_EQ(c.overlaps, 0);
  EXPECT_FALSE(c.bijective());
}
