#include "meshing/curved/features.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::curved {

namespace {
std::map<std::array<int, 2>, std::vector<int>> edge_faces(const SurfaceMesh& mesh) {
  std::map<std::array<int, 2>, std::vector<int>> out;
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3);
      out[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  return out;
}
}  // namespace

std::vector<std::array<int, 2>> detect_feature_edges(const SurfaceMesh& mesh, double angle_deg) {
  const double cos_bound = std::cos(angle_deg * M_PI / 180.0);
  auto normal = [&](int f) {
    const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)),
                          c = mesh.V.row(mesh.F(f, 2));
    return Eigen::Vector3d((b - a).cross(c - a).normalized());
  };
  std::vector<std::array<int, 2>> out;
  for (const auto& [e, faces] : edge_faces(mesh)) {
    if (faces.size() != 2) continue;  // boundary or non-manifold: check rejects those earlier
    if (normal(faces[0]).dot(normal(faces[1])) < cos_bound) out.push_back(e);
  }
  return out;
}

std::vector<std::array<int, 2>> validate_feature_edges(const SurfaceMesh& mesh,
                                                       std::vector<std::array<int, 2>> edges) {
  const auto all = edge_faces(mesh);
  for (auto& e : edges) {
    if (e[0] > e[1]) std::swap(e[0], e[1]);
    if (!all.count(e))
      throw InputError("feature edge (" + std::to_string(e[0]) + ", " + std::to_string(e[1]) +
                       ") is not an edge of the input surface");
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

std::vector<char> feature_vertices(int n, const std::vector<std::array<int, 2>>& edges) {
  std::vector<char> out(n, 0);
  for (const auto& e : edges) out[e[0]] = out[e[1]] = 1;
  return out;
}

}  // namespace curvefem::meshing::curved
