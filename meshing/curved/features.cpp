#include "meshing/curved/features.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
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

std::vector<std::array<int, 2>> drop_small_feature_components(
    const SurfaceMesh& mesh, const std::vector<std::array<int, 2>>& edges, double min_extent,
    const std::vector<double>& scale, int* dropped_components) {
  std::vector<int> parent(std::size_t(mesh.num_vertices()));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int v) {
    while (parent[std::size_t(v)] != v)
      v = parent[std::size_t(v)] = parent[std::size_t(parent[std::size_t(v)])];
    return v;
  };
  for (const auto& e : edges) parent[std::size_t(find(e[0]))] = find(e[1]);
  struct Component {
    Eigen::AlignedBox3d box;
    double scale = HUGE_VAL;  // the smallest at its vertices
    bool kept = false;
  };
  std::map<int, Component> components;
  for (const auto& e : edges)
    for (int v : e) {
      Component& c = components[find(v)];
      c.box.extend(mesh.V.row(v).transpose());
      c.scale = std::min(c.scale, scale.empty() ? 1.0 : scale[std::size_t(v)]);
    }
  int dropped = 0;
  for (auto& [root, c] : components) {
    c.kept = c.box.diagonal().norm() >= min_extent * c.scale;
    dropped += !c.kept;
  }
  if (dropped_components) *dropped_components = dropped;
  std::vector<std::array<int, 2>> out;
  for (const auto& e : edges)
    if (components.at(find(e[0])).kept) out.push_back(e);
  return out;
}

std::vector<std::array<int, 2>> trim_feature_ends(const SurfaceMesh& mesh,
                                                  const std::vector<std::array<int, 2>>& edges,
                                                  double length, const std::vector<double>& scale,
                                                  int* trimmed_ends) {
  std::vector<std::vector<int>> incident(std::size_t(mesh.num_vertices()));  // edge indices
  for (std::size_t i = 0; i < edges.size(); ++i)
    for (int v : edges[i]) incident[std::size_t(v)].push_back(int(i));
  std::vector<char> removed(edges.size(), 0);
  std::vector<int> degree(incident.size());
  for (std::size_t v = 0; v < incident.size(); ++v) degree[v] = int(incident[v].size());
  std::vector<int> open_ends;  // before any cut: a cut's new end is not cut again
  for (int v = 0; v < mesh.num_vertices(); ++v)
    if (degree[std::size_t(v)] == 1) open_ends.push_back(v);
  int ends = 0;
  for (const int v : open_ends) {
    if (degree[std::size_t(v)] != 1) continue;  // reached from the curve's other end
    const double limit = length * (scale.empty() ? 1.0 : scale[std::size_t(v)]);
    if (!(limit > 0)) continue;
    double arc = 0;
    int at = v;
    bool cut = false;
    while (degree[std::size_t(at)] == 1 && arc < limit) {
      int e = -1;
      for (int i : incident[std::size_t(at)])
        if (!removed[std::size_t(i)]) e = i;
      const auto& ab = edges[std::size_t(e)];
      const int next = ab[0] == at ? ab[1] : ab[0];
      removed[std::size_t(e)] = 1;
      cut = true;
      --degree[std::size_t(at)];
      --degree[std::size_t(next)];
      arc += (mesh.V.row(ab[0]) - mesh.V.row(ab[1])).norm();
      at = next;
    }
    ends += cut;
  }
  if (trimmed_ends) *trimmed_ends = ends;
  std::vector<std::array<int, 2>> out;
  for (std::size_t i = 0; i < edges.size(); ++i)
    if (!removed[i]) out.push_back(edges[i]);
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
