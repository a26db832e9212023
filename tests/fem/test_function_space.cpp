#include <gtest/gtest.h>

#include <map>
#include <random>

#include "fem/assembly/tabulation.hpp"
#include "fem/space/function_space.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"

using namespace curvefem;

namespace {
Eigen::Vector3d wobble(const Eigen::Vector3d& x) {
  return x +
         0.04 * Eigen::Vector3d(std::sin(3 * x[1]), std::sin(2 * x[2] + x[0]), std::cos(2 * x[0]));
}
}  // namespace

TEST(FunctionSpace, DofCountsOnStructuredCube) {
  const LagrangeMesh cube = make_cube_tets(2);
  for (int p = 1; p <= 4; ++p) {
    const fem::FunctionSpace s = fem::build_function_space(cube, p);
    const int m = 2 * p + 1;
    EXPECT_EQ(s.num_dofs, m * m * m) << "p=" << p;
    const int boundary =
        static_cast<int>(std::count(s.on_boundary.begin(), s.on_boundary.end(), 1));
    EXPECT_EQ(boundary, m * m * m - (m - 2) * (m - 2) * (m - 2)) << "p=" << p;
    EXPECT_EQ(s.boundary_faces.size(), 6u * 2 * 2 * 2);
  }
}

TEST(FunctionSpace, FieldIsContinuousAcrossEveryInteriorFace) {
  // Random nodal values; evaluate from both cells at random points of each shared face.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 1; k <= 3; ++k) {
    const LagrangeMesh mesh = elevate_order(make_cube_tets(2), k, wobble);
    for (int p = 1; p <= 4; ++p) {
      const fem::FunctionSpace s = fem::build_function_space(mesh, p);
      Eigen::VectorXd values(s.num_dofs);
      for (int i = 0; i < s.num_dofs; ++i) values[i] = u(rng) - 0.5;
      std::map<std::array<int, 3>, std::vector<int>> faces;  // sorted vertex ids → cells
      for (int c = 0; c < mesh.num_cells(); ++c)
        for (int j = 0; j < 4; ++j) {
          std::array<int, 3> f;
          int n = 0;
          for (int i = 0; i < 4; ++i)
            if (i != j) f[n++] = mesh.cells(c, i);
          std::sort(f.begin(), f.end());
          faces[f].push_back(c);
        }
      double worst = 0.0;
      int interior = 0;
      const Eigen::Matrix<double, 4, 3> ref =
          (Eigen::Matrix<double, 4, 3>() << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1).finished();
      for (const auto& [f, cells] : faces) {
        if (cells.size() != 2) continue;
        ++interior;
        for (int trial = 0; trial < 3; ++trial) {
          double b0 = u(rng), b1 = u(rng) * (1 - b0);
          const double bary[3] = {b0, b1, 1 - b0 - b1};
          double val[2];
          for (int side = 0; side < 2; ++side) {
            const int c = cells[side];
            Eigen::Vector3d xi = Eigen::Vector3d::Zero();
            for (int v = 0; v < 3; ++v)
              for (int i = 0; i < 4; ++i)
                if (mesh.cells(c, i) == f[v]) xi += bary[v] * ref.row(i).transpose();
            const auto tab = fem::tabulate(CellKind::tetrahedron, p, xi.transpose());
            val[side] = 0;
            for (int a = 0; a < tab.values.cols(); ++a)
              val[side] += tab.values(0, a) * values[s.cell_dofs(c, a)];
          }
          worst = std::max(worst, std::abs(val[0] - val[1]));
        }
      }
      EXPECT_GT(interior, 50);
      EXPECT_LT(worst, 1e-12) << "k=" << k << " p=" << p;
    }
  }
}

TEST(FunctionSpace, RejectsBadDegree) {
  EXPECT_THROW(fem::build_function_space(make_cube_tets(1), 5), InputError);
  EXPECT_THROW(fem::build_function_space(make_cube_tets(1), 0), InputError);
}
