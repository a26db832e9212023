// Quality flips of straight tet meshes: a known 2-3 flip, and a jittered grid whose boundary,
// volume and conformity must survive.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <map>
#include <random>
#include <set>

#include "meshing/editing/algorithms/tet_flips.hpp"

namespace ed = curvefem::meshing::editing;

namespace {

double volume(const Eigen::MatrixXd& V, const Eigen::MatrixXi& T, int t) {
  const Eigen::Vector3d a = V.row(T(t, 0)), b = V.row(T(t, 1)), c = V.row(T(t, 2)),
                        d = V.row(T(t, 3));
  return (b - a).cross(c - a).dot(d - a) / 6;
}

// Faces with their use count, sorted vertex triples.
std::map<std::array<int, 3>, int> faces(const Eigen::MatrixXi& T) {
  std::map<std::array<int, 3>, int> out;
  for (int t = 0; t < T.rows(); ++t)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> f;
      int m = 0;
      for (int j = 0; j < 4; ++j)
        if (j != skip) f[m++] = T(t, j);
      std::sort(f.begin(), f.end());
      ++out[f];
    }
  return out;
}

std::set<std::array<int, 3>> boundary(const Eigen::MatrixXi& T) {
  std::set<std::array<int, 3>> out;
  for (const auto& [f, n] : faces(T))
    if (n == 1) out.insert(f);
  return out;
}

}  // namespace

TEST(TetFlips, FlatBipyramidFlipsTwoToThree) {
  Eigen::MatrixXd V(5, 3);
  const double s = std::sqrt(3.0) / 2;
  V << 1, 0, 0, -0.5, s, 0, -0.5, -s, 0, 0, 0, 0.3, 0, 0, -0.3;
  Eigen::MatrixXi T(2, 4);
  T << 0, 1, 2, 3, 0, 2, 1, 4;
  ASSERT_GT(volume(V, T, 0), 0);
  ASSERT_GT(volume(V, T, 1), 0);
  const ed::FlipResult r = ed::flip_tets(V, T);
  ASSERT_EQ(r.T.rows(), 3) << r.T;
  for (int t = 0; t < 3; ++t) {
    EXPECT_GT(volume(V, r.T, t), 0);
    const std::set<int> verts = {r.T(t, 0), r.T(t, 1), r.T(t, 2), r.T(t, 3)};
    EXPECT_TRUE(verts.count(3) && verts.count(4)) << "every new tet holds the new edge 3-4";
  }
  EXPECT_EQ(boundary(r.T), boundary(T));
  EXPECT_LT(r.max_energy_after, r.max_energy_before);
  EXPECT_EQ(r.pass.succeeded, 1u);
  // The AMIPS values themselves: flat tets of height 0.3 on a unit-circumradius triangle.
  EXPECT_NEAR(r.max_energy_before, ed::tet_amips(V.row(0), V.row(1), V.row(2), V.row(3)), 1e-12);
}

TEST(TetFlips, JitteredGridKeepsBoundaryVolumeAndConformity) {
  const int n = 5;  // n^3 cells, 6 tets each (Kuhn subdivision)
  auto id = [n](int i, int j, int k) { return (i * (n + 1) + j) * (n + 1) + k; };
  Eigen::MatrixXd V((n + 1) * (n + 1) * (n + 1), 3);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      for (int k = 0; k <= n; ++k) {
        Eigen::Vector3d p(i, j, k);
        const bool inside = i > 0 && i < n && j > 0 && j < n && k > 0 && k < n;
        if (inside) p += Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
        V.row(id(i, j, k)) = p.transpose();
      }
  std::vector<std::array<int, 4>> tets;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          std::array<int, 4> t;
          t[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            t[s + 1] = id(c[0], c[1], c[2]);
          }
          tets.push_back(t);
        }
  Eigen::MatrixXi T(int(tets.size()), 4);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    for (int j = 0; j < 4; ++j) T(int(t), j) = tets[t][j];
    if (volume(V, T, int(t)) < 0) std::swap(T(int(t), 2), T(int(t), 3));
    ASSERT_GT(volume(V, T, int(t)), 0) << "jitter inverted tet " << t;
  }
  double vol = 0;
  for (int t = 0; t < T.rows(); ++t) vol += volume(V, T, t);

  const ed::FlipResult r = ed::flip_tets(V, T);
  EXPECT_GT(r.pass.succeeded, 20u);
  EXPECT_LT(r.max_energy_after, r.max_energy_before);
  EXPECT_LT(r.mean_energy_after, r.mean_energy_before);
  EXPECT_EQ(boundary(r.T), boundary(T));
  double after = 0;
  for (int t = 0; t < r.T.rows(); ++t) {
    ASSERT_GT(volume(V, r.T, t), 0);
    after += volume(V, r.T, t);
  }
  EXPECT_NEAR(after, vol, 1e-9 * vol);
  for (const auto& [f, count] : faces(r.T)) EXPECT_LE(count, 2);
}
