#include "meshing/check/merge_short_edges.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

namespace curvefem::check {

namespace {

struct Edge {
  double length;
  int a, b;
};

}  // namespace

MergeShortEdgesResult merge_short_edges(const SurfaceMesh& input,
                                        const MergeShortEdgesOptions& options) {
  const int nv = input.num_vertices(), nf = input.num_faces();
  Eigen::MatrixXi F = input.F;
  std::vector<char> alive(static_cast<std::size_t>(nf), 1);
  std::vector<std::vector<int>> vf(static_cast<std::size_t>(nv));  // incident faces (alive or not)
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) vf[std::size_t(F(f, k))].push_back(f);
  std::vector<int> parent(static_cast<std::size_t>(nv));
  for (int v = 0; v < nv; ++v) parent[std::size_t(v)] = v;
  auto find = [&](int v) {
    while (parent[std::size_t(v)] != v) v = parent[std::size_t(v)];
    return v;
  };
  auto point = [&](int v) { return Eigen::Vector3d(input.V.row(v).transpose()); };
  auto normal = [&](int a, int b, int c) {
    return Eigen::Vector3d((point(b) - point(a)).cross(point(c) - point(a)));
  };
  auto short_edges = [&] {
    std::vector<Edge> out;
    std::set<std::pair<int, int>> seen;
    for (int f = 0; f < nf; ++f) {
      if (!alive[std::size_t(f)]) continue;
      for (int k = 0; k < 3; ++k) {
        const int a = F(f, k), b = F(f, (k + 1) % 3);
        const double l = (point(a) - point(b)).norm();
        if (l < options.max_length && seen.emplace(std::min(a, b), std::max(a, b)).second)
          out.push_back({l, std::min(a, b), std::max(a, b)});
      }
    }
    std::sort(out.begin(), out.end(), [](const Edge& x, const Edge& y) {
      return std::tie(x.length, x.a, x.b) < std::tie(y.length, y.a, y.b);
    });
    return out;
  };
  auto neighbours = [&](int v) {
    std::set<int> out;
    for (int f : vf[std::size_t(v)])
      if (alive[std::size_t(f)])
        for (int k = 0; k < 3; ++k)
          if (F(f, k) != v) out.insert(F(f, k));
    return out;
  };
  const double cos_turn = std::cos(options.max_normal_turn_deg * M_PI / 180.0);

  MergeShortEdgesResult result;
  result.candidates = int(short_edges().size());
  bool changed = true;
  while (changed) {
    changed = false;
    for (const Edge& e : short_edges()) {
      const int a = e.a, b = e.b;
      if (find(a) != a || find(b) != b) continue;  // an end merged away in this pass
      std::vector<int> shared;                     // the edge's faces
      for (int f : vf[std::size_t(a)])
        if (alive[std::size_t(f)] && (F(f, 0) == b || F(f, 1) == b || F(f, 2) == b))
          shared.push_back(f);
      if (shared.size() != 2) continue;
      std::set<int> opposite;
      for (int f : shared)
        for (int k = 0; k < 3; ++k)
          if (F(f, k) != a && F(f, k) != b) opposite.insert(F(f, k));
      const std::set<int> na = neighbours(a), nb = neighbours(b);
      std::set<int> common;
      std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(),
                            std::inserter(common, common.begin()));
      if (common != opposite || opposite.size() != 2) continue;  // the link condition
      // The worst turn of the faces that keep the removed end, with it moved onto the kept one;
      // -2 where one would become degenerate or turn by more than the bound.
      auto worst_cos = [&](int kept, int removed) {
        double worst = 1.0;
        for (int f : vf[std::size_t(removed)]) {
          if (!alive[std::size_t(f)] || std::find(shared.begin(), shared.end(), f) != shared.end())
            continue;
          std::array<int, 3> c = {F(f, 0), F(f, 1), F(f, 2)};
          const Eigen::Vector3d before = normal(c[0], c[1], c[2]);
          for (int& v : c)
            if (v == removed) v = kept;
          const Eigen::Vector3d after = normal(c[0], c[1], c[2]);
          double scale = 0;
          for (int k = 0; k < 3; ++k)
            scale = std::max(scale, (point(c[k]) - point(c[(k + 1) % 3])).squaredNorm());
          if (!(after.norm() > 1e-12 * scale) || !(before.norm() > 0)) return -2.0;
          worst = std::min(worst, before.normalized().dot(after.normalized()));
        }
        return worst >= cos_turn ? worst : -2.0;
      };
      const double keep_a = worst_cos(a, b), keep_b = worst_cos(b, a);
      if (keep_a < -1 && keep_b < -1) continue;
      const int kept = keep_a >= keep_b ? a : b, removed = kept == a ? b : a;
      for (int f : shared) alive[std::size_t(f)] = 0;
      for (int f : vf[std::size_t(removed)]) {
        if (!alive[std::size_t(f)]) continue;
        for (int k = 0; k < 3; ++k)
          if (F(f, k) == removed) F(f, k) = kept;
        vf[std::size_t(kept)].push_back(f);
      }
      parent[std::size_t(removed)] = kept;
      result.merged.push_back({removed, kept, e.length});
      result.max_moved = std::max(result.max_moved, e.length);
      changed = true;
    }
  }
  result.refused = int(short_edges().size());

  std::vector<int> id(static_cast<std::size_t>(nv), -1);
  int n = 0;
  for (int v = 0; v < nv; ++v)
    if (find(v) == v) id[std::size_t(v)] = n++;
  result.vertex_map.resize(std::size_t(nv));
  for (int v = 0; v < nv; ++v) result.vertex_map[std::size_t(v)] = id[std::size_t(find(v))];
  result.mesh.V.resize(n, 3);
  for (int v = 0; v < nv; ++v)
    if (id[std::size_t(v)] >= 0) result.mesh.V.row(id[std::size_t(v)]) = input.V.row(v);
  for (int f = 0; f < nf; ++f)
    if (alive[std::size_t(f)]) result.face_origin.push_back(f);
  const int m = int(result.face_origin.size());
  result.mesh.F.resize(m, 3);
  if (input.has_tags()) result.mesh.tags.resize(m);
  for (int i = 0; i < m; ++i) {
    const int f = result.face_origin[std::size_t(i)];
    for (int k = 0; k < 3; ++k) result.mesh.F(i, k) = id[std::size_t(F(f, k))];
    if (input.has_tags()) result.mesh.tags(i) = input.tags(f);
  }
  result.mesh.tag_names = input.tag_names;
  return result;
}

}  // namespace curvefem::check
