// Cutting a surface into charts: union-find of face corners across uncut edges, then the disk
// test per chart (V − E + F and the boundary loops of the cut mesh).
#include "meshing/param/cut_mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

#include "meshing/core/error.hpp"

namespace curvefem::meshing::param {

namespace {

struct UnionFind {
  std::vector<int> up;
  explicit UnionFind(int n) : up(n) { std::iota(up.begin(), up.end(), 0); }
  int find(int a) {
    while (up[a] != a) a = up[a] = up[up[a]];
    return a;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) up[std::max(a, b)] = std::min(a, b);
  }
};

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

std::string chart_label(const SurfaceMesh& mesh, int chart, int face) {
  std::string s = "chart " + std::to_string(chart);
  if (mesh.has_tags()) {
    const int tag = mesh.tags[face];
    auto it = mesh.tag_names.find(tag);
    s += " (group '" + (it != mesh.tag_names.end() ? it->second : std::to_string(tag)) + "')";
  }
  return s;
}

}  // namespace

CutMesh cut_into_charts(const SurfaceMesh& mesh, const std::vector<std::array<int, 2>>& seams,
                        const CutOptions& options) {
  const int nf = mesh.num_faces(), nv = mesh.num_vertices();
  if (nf == 0) throw InputError("param: the surface has no face");
  for (int f = 0; f < nf; ++f) {
    const int a = mesh.F(f, 0), b = mesh.F(f, 1), c = mesh.F(f, 2);
    if (a == b || b == c || a == c) {
      ErrorContext ctx;
      ctx.face = f;
      throw InputError("param: degenerate face (repeated vertex)", ctx);
    }
    const Eigen::Vector3d e1 = mesh.V.row(b) - mesh.V.row(a), e2 = mesh.V.row(c) - mesh.V.row(a);
    if (!(e1.cross(e2).norm() > 0)) {
      ErrorContext ctx;
      ctx.face = f;
      throw InputError("param: degenerate face (zero area in 3D): no rest shape", ctx);
    }
  }
  // Half-edges by undirected edge: (face, local edge k = corner k → corner k+1).
  std::unordered_map<std::uint64_t, std::vector<int>> edges;
  edges.reserve(std::size_t(3 * nf));
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k)
      edges[edge_key(mesh.F(f, k), mesh.F(f, (k + 1) % 3))].push_back(3 * f + k);
  std::unordered_set<std::uint64_t> cut;
  for (std::size_t s = 0; s < seams.size(); ++s) {
    const auto [a, b] = seams[s];
    if (a < 0 || b < 0 || a >= nv || b >= nv || !edges.count(edge_key(a, b))) {
      ErrorContext ctx;
      ctx.vertex = a;
      throw InputError("param: seam " + std::to_string(s) + " (" + std::to_string(a) + ", " +
                           std::to_string(b) + ") is not an edge of the mesh",
                       ctx);
    }
    cut.insert(edge_key(a, b));
  }
  UnionFind corners(3 * nf), faces(nf);
  for (const auto& [key, hes] : edges) {
    if (hes.size() > 2) {
      ErrorContext ctx;
      ctx.face = hes[0] / 3;
      ctx.vertex = mesh.F(hes[0] / 3, hes[0] % 3);
      throw InputError("param: non-manifold edge (" + std::to_string(hes.size()) + " faces)", ctx);
    }
    if (hes.size() < 2 || cut.count(key)) continue;
    const int f = hes[0] / 3, k = hes[0] % 3, g = hes[1] / 3, l = hes[1] % 3;
    if (options.split_groups && mesh.has_tags() && mesh.tags[f] != mesh.tags[g]) continue;
    if (mesh.F(f, k) == mesh.F(g, l)) {
      ErrorContext ctx;
      ctx.face = g;
      throw InputError("param: faces " + std::to_string(f) + " and " + std::to_string(g) +
                           " have opposite orientations across their shared edge",
                       ctx);
    }
    corners.unite(3 * f + k, 3 * g + (l + 1) % 3);  // corner of fa in g
    corners.unite(3 * f + (k + 1) % 3, 3 * g + l);  // corner of fb in g
    faces.unite(f, g);
  }
  CutMesh out;
  out.F.resize(nf, 3);
  std::vector<int> uv_of_root(3 * nf, -1), parent;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int r = corners.find(3 * f + k);
      if (uv_of_root[r] < 0) {
        uv_of_root[r] = int(parent.size());
        parent.push_back(mesh.F(f, k));
      }
      out.F(f, k) = uv_of_root[r];
    }
  const int nu = int(parent.size());
  out.parent = Eigen::Map<Eigen::VectorXi>(parent.data(), nu);
  out.V.resize(nu, 3);
  for (int u = 0; u < nu; ++u) out.V.row(u) = mesh.V.row(parent[u]);
  out.chart.resize(nf);
  std::vector<int> chart_of_root(nf, -1), first_face;
  for (int f = 0; f < nf; ++f) {
    const int r = faces.find(f);
    if (chart_of_root[r] < 0) {
      chart_of_root[r] = out.num_charts++;
      first_face.push_back(f);
    }
    out.chart[f] = chart_of_root[r];
  }
  // Per chart: counts for χ and the boundary loop(s) of the cut mesh.
  const int nc = out.num_charts;
  std::vector<long long> cv(nc, 0), ce(nc, 0), cf(nc, 0);
  std::vector<int> chart_of_uv(nu, -1);
  std::unordered_map<std::uint64_t, int> uv_edges;  // undirected UV edge → half-edge count
  for (int f = 0; f < nf; ++f) {
    ++cf[out.chart[f]];
    for (int k = 0; k < 3; ++k) {
      const int u = out.F(f, k);
      if (chart_of_uv[u] < 0) {
        chart_of_uv[u] = out.chart[f];
        ++cv[out.chart[f]];
      }
      if (++uv_edges[edge_key(u, out.F(f, (k + 1) % 3))] == 1) ++ce[out.chart[f]];
    }
  }
  std::vector<int> next(nu, -1);  // boundary half-edge a → b, stored at a
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = out.F(f, k), b = out.F(f, (k + 1) % 3);
      if (uv_edges[edge_key(a, b)] == 1) {
        CF_VERIFY(next[a] < 0, "a UV vertex has two outgoing boundary half-edges");
        next[a] = b;
      }
    }
  std::vector<std::vector<std::vector<int>>> loops(nc);
  std::vector<char> seen(nu, 0);
  for (int u = 0; u < nu; ++u) {
    if (next[u] < 0 || seen[u]) continue;
    std::vector<int> loop;
    for (int w = u; !seen[w]; w = next[w]) {
      seen[w] = 1;
      loop.push_back(w);
      CF_VERIFY(next[w] >= 0, "open boundary chain");
    }
    loops[chart_of_uv[u]].push_back(std::move(loop));
  }
  out.boundary_loops.resize(nc);
  out.chart_names.resize(nc);
  for (int c = 0; c < nc; ++c) {
    out.chart_names[c] = chart_label(mesh, c, first_face[c]);
    const long long chi = cv[c] - ce[c] + cf[c];
    if (chi != 1 || loops[c].size() != 1) {
      ErrorContext ctx;
      ctx.face = first_face[c];
      throw InputError("param: " + out.chart_names[c] + " is not a disk: Euler characteristic " +
                           std::to_string(chi) + ", " + std::to_string(loops[c].size()) +
                           " boundary loop(s) (" + std::to_string(cf[c]) +
                           " faces); cut it into disks with seams (--seams FILE) or OBJ groups",
                       ctx);
    }
    out.boundary_loops[c] = std::move(loops[c][0]);
  }
  return out;
}

RestShapes rest_shapes(const CutMesh& cut) {
  const int nf = cut.num_faces();
  RestShapes r;
  r.G.resize(nf);
  r.area.resize(nf);
  Eigen::Matrix<double, 3, 2> B;
  B << -1, -1, 1, 0, 0, 1;
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3d p0 = cut.V.row(cut.F(f, 0)), p1 = cut.V.row(cut.F(f, 1)),
                          p2 = cut.V.row(cut.F(f, 2));
    const Eigen::Vector3d e1 = p1 - p0, e2 = p2 - p0;
    const double l1 = e1.norm(), twice_area = e1.cross(e2).norm();
    Eigen::Matrix2d Dm;  // columns: the edges in the frame (e1 along x, normal × e1 along y)
    Dm << l1, e1.dot(e2) / l1, 0, twice_area / l1;
    r.G[f] = B * Dm.inverse();
    r.area[f] = 0.5 * twice_area;
  }
  return r;
}

}  // namespace curvefem::meshing::param
