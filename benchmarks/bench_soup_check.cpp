// Time of the soup self-intersection check (meshing/check, the rule the curved mesher's
// embedding repair and the validator apply to their sampled boundaries) on an OBJ surface whose
// every triangle is cut into m × m (points on edges and corners shared, as sample_middle does).
//   cmake --build build --target curvefem_bench_soup_check
//   build/benchmarks/curvefem_bench_soup_check ../shared/data/dev/menger_sponge.obj 6
// Prints the triangle count, the pairs found and the seconds of three runs.
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "meshing/check/self_intersections.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s surface.obj [m = 6]\n", argv[0]);
    return 2;
  }
  std::ifstream in(argv[1]);
  const int m = argc > 2 ? std::atoi(argv[2]) : 6;
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<int, 3>> f;
  for (std::string line; std::getline(in, line);) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      double x, y, z;
      s >> x >> y >> z;
      v.emplace_back(x, y, z);
    } else if (tag == "f") {
      std::array<int, 3> a{};
      for (int& i : a) {
        std::string w;
        s >> w;
        i = std::stoi(w.substr(0, w.find('/'))) - 1;
      }
      f.push_back(a);
    }
  }
  std::map<std::array<int, 3>, int> shared;  // (corner) or (lo vertex, hi vertex, steps from lo)
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<int, 3>> tris;
  auto point = [&](const std::array<int, 3>& face, int i, int j) {
    const int w[3] = {m - i - j, i, j};
    std::array<int, 3> key{-1, -1, -1};
    const int nz = (w[0] > 0) + (w[1] > 0) + (w[2] > 0);
    if (nz == 1) {
      key = {face[w[0] > 0 ? 0 : (w[1] > 0 ? 1 : 2)], -1, -1};
    } else if (nz == 2) {
      int a = -1, b = -1;
      for (int c = 0; c < 3; ++c)
        if (w[c] > 0) (a < 0 ? a : b) = c;
      int va = face[a], vb = face[b], wa = w[a];
      if (va > vb) std::swap(va, vb), wa = m - wa;
      key = {va, vb, wa};
    }
    if (key[0] >= 0)
      if (const auto it = shared.find(key); it != shared.end()) return it->second;
    points.push_back((w[0] * v[face[0]] + w[1] * v[face[1]] + w[2] * v[face[2]]) / m);
    if (key[0] >= 0) shared[key] = int(points.size()) - 1;
    return int(points.size()) - 1;
  };
  for (const auto& face : f) {
    std::vector<std::vector<int>> id(m + 1, std::vector<int>(m + 1, -1));
    for (int j = 0; j <= m; ++j)
      for (int i = 0; i + j <= m; ++i) id[i][j] = point(face, i, j);
    for (int j = 0; j < m; ++j)
      for (int i = 0; i + j < m; ++i) {
        tris.push_back({id[i][j], id[i + 1][j], id[i][j + 1]});
        if (i + j + 1 < m) tris.push_back({id[i + 1][j], id[i + 1][j + 1], id[i][j + 1]});
      }
  }
  Eigen::MatrixXd V(Eigen::Index(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i) V.row(Eigen::Index(i)) = points[i].transpose();
  Eigen::MatrixXi F(Eigen::Index(tris.size()), 3);
  for (std::size_t i = 0; i < tris.size(); ++i)
    F.row(Eigen::Index(i)) << tris[i][0], tris[i][1], tris[i][2];
  const auto degenerate = curvefem::check::exactly_degenerate_faces(V, F);
  for (int run = 0; run < 3; ++run) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = curvefem::check::find_self_intersections(
        V, F, degenerate, true, curvefem::check::SelfIntersectionEngine::soup);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%zu triangles, %zu pairs, %.3f s\n", tris.size(), r.pairs.size(), s);
  }
}
