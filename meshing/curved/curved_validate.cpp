#include "meshing/curved/curved_validate.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"
#include "meshing/curved/element_distortion.hpp"
#include "meshing/curved/jacobian_certificate.hpp"

namespace curvefem::meshing::curved {

namespace {

std::array<int, 3> sorted3(int a, int b, int c) {
  std::array<int, 3> t{a, b, c};
  std::sort(t.begin(), t.end());
  return t;
}

// The curved boundary as flat triangles: an m×m lattice per triangle; points on a shared edge or
// corner are computed once (from the first triangle that has them), so the soup is welded.
void subdivide_boundary(const LagrangeMesh& b, int m, Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
  std::map<std::array<int, 3>, int> shared;  // (lo corner node, hi corner node, steps from lo)
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<int, 3>> tris;
  const int nb = b.num_cells();
  for (int f = 0; f < nb; ++f) {
    const int c[3] = {b.cells(f, 0), b.cells(f, 1), b.cells(f, 2)};
    std::vector<int> id((m + 1) * (m + 2) / 2);
    auto index = [m](int i, int j) { return j * (m + 1) - j * (j - 1) / 2 + i; };  // i + j <= m
    for (int j = 0; j <= m; ++j)
      for (int i = 0; i + j <= m; ++i) {
        const int a0 = m - i - j;  // barycentric weights (a0, i, j) on corners (0, 1, 2)
        std::array<int, 3> key{-1, -1, -1};
        const int w[3] = {a0, i, j};
        const int nz = (a0 > 0) + (i > 0) + (j > 0);
        if (nz == 1) {
          const int corner = a0 > 0 ? 0 : (i > 0 ? 1 : 2);
          key = {c[corner], c[corner], 0};
        } else if (nz == 2) {
          const int p = a0 == 0 ? 1 : 0, q = j == 0 ? 1 : 2;
          key = c[p] < c[q] ? std::array<int, 3>{c[p], c[q], w[q]}
                            : std::array<int, 3>{c[q], c[p], w[p]};
        }
        int pid = -1;
        if (key[0] >= 0) {
          if (auto it = shared.find(key); it != shared.end()) pid = it->second;
        }
        if (pid < 0) {
          pid = int(points.size());
          points.push_back(b.map(f, Eigen::Vector3d(double(i) / m, double(j) / m, 0)));
          if (key[0] >= 0) shared[key] = pid;
        }
        id[index(i, j)] = pid;
      }
    for (int j = 0; j < m; ++j)
      for (int i = 0; i + j < m; ++i) {
        tris.push_back({id[index(i, j)], id[index(i + 1, j)], id[index(i, j + 1)]});
        if (i + j + 1 < m)
          tris.push_back({id[index(i + 1, j)], id[index(i + 1, j + 1)], id[index(i, j + 1)]});
      }
  }
  V.resize(Eigen::Index(points.size()), 3);
  for (std::size_t p = 0; p < points.size(); ++p) V.row(Eigen::Index(p)) = points[p];
  F.resize(Eigen::Index(tris.size()), 3);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) F(Eigen::Index(t), k) = tris[t][k];
}

}  // namespace

CurvedValidation validate_curved_mesh(const LagrangeMesh& mesh, const BoundaryMap& map,
                                      const SurfaceMesh& input, int subdivision) {
  const auto t0 = std::chrono::steady_clock::now();
  CurvedValidation r;
  const int nt = mesh.num_cells(), k = mesh.order;
  r.tets = nt;

  // Positivity certificates and quality.
  std::vector<JacobianVerdict> verdict(nt);
  std::vector<double> sj(nt), mips(nt);
  std::vector<ElementDistortion> distortion(nt);
  tbb::parallel_for(0, nt, [&](int c) {
    Eigen::MatrixXd X(mesh.cells.cols(), 3);
    for (int n = 0; n < X.rows(); ++n) X.row(n) = mesh.nodes.row(mesh.cells(c, n));
    verdict[c] = certify_tet_jacobian(k, X).verdict;
    sj[c] = min_scaled_jacobian(k, X);
    mips[c] = curved_mips(k, X);
    distortion[c] = element_distortion(k, X);
  });
  r.min_scaled_jacobian = nt ? HUGE_VAL : 0;
  for (int c = 0; c < nt; ++c) {
    if (verdict[c] == JacobianVerdict::non_positive) ++r.non_positive_tets;
    if (verdict[c] == JacobianVerdict::undecided) ++r.undecided_tets;
    if (verdict[c] != JacobianVerdict::positive && r.first_bad_tet < 0) r.first_bad_tet = c;
    r.min_scaled_jacobian = std::min(r.min_scaled_jacobian, sj[c]);
    r.tets_sj_below_1e2 += sj[c] < 1e-2;
    r.tets_sj_below_1e3 += sj[c] < 1e-3;
    r.mean_mips += mips[c] / std::max(nt, 1);
    r.max_mips = std::max(r.max_mips, mips[c]);
    const ElementDistortion& d = distortion[c];
    r.min_jacobian_ratio = std::min(r.min_jacobian_ratio, d.jacobian_ratio);
    r.max_d2 = std::max(r.max_d2, d.d2);
    r.max_d3 = std::max(r.max_d3, d.d3);
    r.mean_d2 += d.d2 / std::max(nt, 1);
    r.mean_d3 += d.d3 / std::max(nt, 1);
    if (mesh.cell_tags.size() == nt) {
      auto& q = r.quality_by_tag[mesh.cell_tags[c]];
      ++q.tets;
      q.min_scaled_jacobian = std::min(q.min_scaled_jacobian, sj[c]);
      q.tets_sj_below_1e2 += sj[c] < 1e-2;
      q.tets_sj_below_1e3 += sj[c] < 1e-3;
      q.mean_mips += mips[c];
      q.max_mips = std::max(q.max_mips, mips[c]);
      q.min_jacobian_ratio = std::min(q.min_jacobian_ratio, d.jacobian_ratio);
      q.max_d2 = std::max(q.max_d2, d.d2);
      q.max_d3 = std::max(q.max_d3, d.d3);
      q.mean_d2 += d.d2;
      q.mean_d3 += d.d3;
    }
  }
  for (auto& [tag, q] : r.quality_by_tag) {
    q.mean_mips /= std::max(q.tets, 1);
    q.mean_d2 /= std::max(q.tets, 1);
    q.mean_d3 /= std::max(q.tets, 1);
  }
  r.cell_certificate.resize(nt);
  for (int c = 0; c < nt; ++c)
    r.cell_certificate[c] = verdict[c] == JacobianVerdict::positive       ? 1
                            : verdict[c] == JacobianVerdict::non_positive ? -1
                                                                          : 0;
  r.cell_scaled_jacobian = std::move(sj);
  r.cell_mips = std::move(mips);
  r.cell_jacobian_ratio.resize(nt);
  r.cell_d2.resize(nt);
  r.cell_d3.resize(nt);
  for (int c = 0; c < nt; ++c) {
    r.cell_jacobian_ratio[c] = distortion[c].jacobian_ratio;
    r.cell_d2[c] = distortion[c].d2;
    r.cell_d3[c] = distortion[c].d3;
  }

  // Boundary faces of the volume (by corner nodes) against the map's triangles.
  {
    // With an exterior (cells tagged 3 and 4) the curved surface is the boundary of the inside
    // (tags 1 and 2), and the whole mesh's boundary must be the box.
    const bool has_tags = mesh.cell_tags.size() == nt;
    for (int c = 0; c < nt && has_tags; ++c) r.exterior |= mesh.cell_tags[c] >= 3;
    std::map<std::array<int, 3>, int> count, count_all;
    // Outward for a positively oriented tet (corner 0 at the origin of its frame).
    static const int faces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    std::map<std::array<int, 3>, std::array<int, 3>> outward;
    for (int c = 0; c < nt; ++c)
      for (const auto& fc : faces) {
        const std::array<int, 3> t{mesh.cells(c, fc[0]), mesh.cells(c, fc[1]),
                                   mesh.cells(c, fc[2])};
        const auto f = sorted3(t[0], t[1], t[2]);
        ++count_all[f];
        if (!r.exterior || mesh.cell_tags[c] <= 2) {
          ++count[f];
          outward[f] = t;
        }
      }
    std::set<std::array<int, 3>> volume_boundary;
    std::vector<std::array<int, 3>> oriented_boundary;
    for (const auto& [f, n] : count)
      if (n == 1) {
        volume_boundary.insert(f);
        oriented_boundary.push_back(outward.at(f));
      }
    r.boundary_limits = boundary_limits(mesh.nodes, oriented_boundary);
    if (r.exterior) {
      const auto [lo, hi] = vertex_bounding_box(mesh);
      for (const auto& [f, n] : count_all) {
        if (n != 1) continue;
        ++r.exterior_boundary_faces;
        bool on_box = false;
        for (int axis = 0; axis < 3 && !on_box; ++axis)
          for (double plane : {lo[axis], hi[axis]}) {
            bool all = true;
            for (int v : f) all &= mesh.nodes(v, axis) == plane;
            on_box |= all;
          }
        if (!on_box) ++r.exterior_faces_off_box;
      }
    }
    const auto& vol = map.boundary_node_to_volume;
    std::set<std::array<int, 3>> map_boundary;
    for (int f = 0; f < map.boundary.num_cells(); ++f) {
      int v[3];
      for (int j = 0; j < 3; ++j) {
        const int b = map.boundary.cells(f, j);
        v[j] = vol.size() ? vol[b] : -1;
      }
      map_boundary.insert(sorted3(v[0], v[1], v[2]));
    }
    r.boundary_faces = int(volume_boundary.size());
    for (const auto& f : map_boundary)
      if (!volume_boundary.count(f)) ++r.boundary_faces_missing;
    for (const auto& f : volume_boundary)
      if (!map_boundary.count(f)) ++r.boundary_faces_extra;
    for (int b = 0; b < map.boundary.num_nodes(); ++b)
      if (vol.size() == 0 || vol[b] < 0 || vol[b] >= mesh.num_nodes() ||
          (map.boundary.nodes.row(b) - mesh.nodes.row(vol[b])).cwiseAbs().maxCoeff() != 0)
        ++r.boundary_node_mismatches;
  }

  // Parametric quality of the curved boundary (a diagnostic, not part of `valid`): per boundary
  // triangle, the smallest area element |x_ξ × x_η| over its order-4k lattice — 0 where its
  // normal turns against the plane of its corners (the patch folds) — over the largest.
  {
    const auto& lattice = lagrange_lattice(CellKind::triangle, k);
    const int m = 4 * k;
    std::vector<Eigen::MatrixXd> grads;
    for (int j = 0; j <= m; ++j)
      for (int i = 0; i + j <= m; ++i)
        grads.push_back(lagrange_shape_gradients(CellKind::triangle, k,
                                                 Eigen::Vector3d(double(i) / m, double(j) / m, 0)));
    int corner[3] = {-1, -1, -1};
    for (std::size_t n = 0; n < lattice.size(); ++n)
      for (int c = 0; c < 3; ++c)
        if (lattice[n][c] == k) corner[c] = int(n);
    const auto& cells = map.boundary.cells;
    for (int f = 0; f < cells.rows(); ++f) {
      auto X = [&](int n) -> Eigen::Vector3d { return map.boundary.nodes.row(cells(f, n)); };
      const Eigen::Vector3d n0 = (X(corner[1]) - X(corner[0])).cross(X(corner[2]) - X(corner[0]));
      double lo = HUGE_VAL, hi = 0;
      for (const Eigen::MatrixXd& g : grads) {
        Eigen::Vector3d xu = Eigen::Vector3d::Zero(), xv = Eigen::Vector3d::Zero();
        for (Eigen::Index n = 0; n < cells.cols(); ++n) {
          xu += g(n, 0) * X(int(n));
          xv += g(n, 1) * X(int(n));
        }
        const Eigen::Vector3d c = xu.cross(xv);
        const double a = c.dot(n0) > 0 ? c.norm() : 0.0;
        lo = std::min(lo, a);
        hi = std::max(hi, a);
      }
      const double ratio = hi > 0 ? lo / hi : 0.0;
      r.min_boundary_area_ratio = std::min(r.min_boundary_area_ratio, ratio);
      r.boundary_faces_folded += ratio == 0;
      r.boundary_faces_distorted += ratio < 0.1;
    }
  }

  // Embedding of the curved boundary on a fine subdivision.
  {
    r.subdivision = subdivision > 0 ? subdivision : 2 * k;
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    subdivide_boundary(map.boundary, r.subdivision, V, F);
    const auto degenerate = check::exactly_degenerate_faces(V, F);
    const auto si = check::find_self_intersections(V, F, degenerate, false,
                                                   check::SelfIntersectionEngine::soup);
    r.boundary_self_intersections =
        int(si.pairs.size()) + int(std::count(degenerate.begin(), degenerate.end(), 1));
  }

  // Distance bound and local orientation of φ.
  {
    const double unit = bbox_longest_edge(input.V);
    r.eps_field = !map.eps_scale.empty();
    if (r.eps_field && int(map.eps_scale.size()) != input.num_vertices())
      throw InputError("validate: the map's eps_scale has " + std::to_string(map.eps_scale.size()) +
                       " entries for an input of " + std::to_string(input.num_vertices()) +
                       " vertices");
    std::vector<char> referenced(input.num_vertices(), 0);
    for (int f = 0; f < input.num_faces(); ++f)
      for (int c = 0; c < 3; ++c) referenced[input.F(f, c)] = 1;
    for (int v = 0; v < input.num_vertices(); ++v) {
      if (!referenced[v]) continue;
      if (v >= map.num_input_vertices() || map.vertex_face[v] < 0) {
        ++r.unmapped_vertices;
        continue;
      }
      const double d = (map.image(v) - input.V.row(v).transpose()).norm() / unit;
      if (d > r.max_distance_rel) {
        r.max_distance_rel = d;
        r.max_distance_vertex = v;
      }
      const double scaled = r.eps_field ? d / map.eps_scale[std::size_t(v)] : d;
      if (scaled > r.max_scaled_distance_rel) {
        r.max_scaled_distance_rel = scaled;
        r.max_scaled_distance_vertex = v;
      }
    }
    // Distance points: the input point from its input face and barycentric coordinates (its
    // position is not taken from the mesher), against its image.
    r.distance_points = map.num_points();
    for (int i = 0; i < map.num_points(); ++i) {
      const int t = map.point_input_face[i];
      if (t < 0 || t >= input.num_faces()) {
        ++r.bad_distance_points;
        continue;
      }
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      for (int c = 0; c < 3; ++c)
        p += map.point_bary(i, c) * input.V.row(input.F(t, c)).transpose();
      const double d = (map.point_image(i) - p).norm() / unit;
      if (d > r.points_max_distance_rel) {
        r.points_max_distance_rel = d;
        r.points_max_distance_point = i;
      }
      r.points_max_scaled_distance_rel =
          std::max(r.points_max_scaled_distance_rel,
                   d / map.eps_scale_at(t, map.point_bary.row(i).transpose(), input.F));
    }
    if (r.unmapped_vertices == 0 && map.num_input_vertices() >= input.num_vertices())
      for (int f = 0; f < input.num_faces(); ++f) {
        const int a = input.F(f, 0), b = input.F(f, 1), c = input.F(f, 2);
        if (map.vertex_face[a] != map.vertex_face[b] || map.vertex_face[a] != map.vertex_face[c])
          continue;
        ++r.input_faces_checked;
        const Eigen::Vector2d pa = map.vertex_uv.row(a), pb = map.vertex_uv.row(b),
                              pc = map.vertex_uv.row(c);
        const Eigen::Vector2d e1 = pb - pa, e2 = pc - pa;
        if (!(e1.x() * e2.y() - e1.y() * e2.x() > 0)) ++r.flipped_input_faces;
      }
  }
  // Feature edges: where each end's image sits on the boundary triangles (a corner node, or the
  // interior of the edge between two corner nodes), then one boundary edge holding both.
  r.feature_edges = int(map.feature_edges.size());
  if (!map.feature_edges.empty()) {
    std::set<std::pair<int, int>> edges;
    const auto& cells = map.boundary.cells;
    for (int f = 0; f < cells.rows(); ++f)
      for (int c = 0; c < 3; ++c) {
        const int a = cells(f, c), b = cells(f, (c + 1) % 3);
        edges.insert({std::min(a, b), std::max(a, b)});
      }
    // An input edge between two singular vertices is split by the shell (a pinch split at its
    // midpoint, bevel points: shell vertices that are no input vertex's image). Its image is then
    // a path of boundary edges through such corner nodes, which must lie on the input edge.
    std::map<int, std::vector<int>> corner_neighbours;
    for (const auto& [a, b] : edges) {
      corner_neighbours[a].push_back(b);
      corner_neighbours[b].push_back(a);
    }
    std::set<int> images;  // corner nodes that are images of input vertices
    for (int v = 0; v < map.num_input_vertices(); ++v) {
      const int f = map.vertex_face[v];
      if (f < 0 || f >= cells.rows()) continue;
      const double u = map.vertex_uv(v, 0), w = map.vertex_uv(v, 1), l[3] = {1 - u - w, u, w};
      for (int c = 0; c < 3; ++c)
        if (std::abs(l[c] - 1) <= 1e-9) images.insert(cells(f, c));
    }
    const double unit = bbox_longest_edge(input.V);
    // Does boundary node m lie on the input segment from vertex va to vertex vb?
    auto on_input_segment = [&](int va, int vb, int m) {
      const Eigen::Vector3d A = input.V.row(va), B = input.V.row(vb);
      const Eigen::Vector3d X = map.boundary.nodes.row(m);
      const double t = std::clamp((X - A).dot(B - A) / (B - A).squaredNorm(), 0.0, 1.0);
      return (A + t * (B - A) - X).norm() <= 1e-9 * unit;
    };
    auto through_split_point = [&](int va, int vb, int a, int b) {
      auto on_segment = [&](int m) { return on_input_segment(va, vb, m); };
      // Breadth-first from a to b through corner nodes on the segment that no input vertex maps
      // to (the shell's split points: pinch splits and bevel points, several per edge).
      std::vector<int> frontier{a};
      std::set<int> seen{a};
      for (int step = 0; step < 16 && !frontier.empty(); ++step) {
        std::vector<int> next;
        for (int x : frontier)
          for (int m : corner_neighbours[x]) {
            if (m == b && x != a) return true;
            if (seen.count(m) || images.count(m) || !on_segment(m)) continue;
            seen.insert(m);
            next.push_back(m);
          }
        frontier = std::move(next);
      }
      return false;
    };
    // {node, -1}: at corner node; {a, b} (a < b): inside that edge; {-1, -1}: off the edges.
    auto where = [&](int v) -> std::pair<int, int> {
      if (v < 0 || v >= map.num_input_vertices()) return {-1, -1};
      const int f = map.vertex_face[v];
      if (f < 0 || f >= cells.rows()) return {-1, -1};
      const double u = map.vertex_uv(v, 0), w = map.vertex_uv(v, 1);
      const double l[3] = {1 - u - w, u, w};
      constexpr double tol = 1e-9;
      int zeros = 0, nonzero = -1;
      for (int c = 0; c < 3; ++c)
        if (std::abs(l[c]) <= tol)
          ++zeros;
        else
          nonzero = c;
      if (zeros == 2) return {int(cells(f, nonzero)), -1};
      if (zeros != 1) return {-1, -1};
      int a = -1, b = -1;
      for (int c = 0; c < 3; ++c)
        if (std::abs(l[c]) > tol) (a < 0 ? a : b) = int(cells(f, c));
      return {std::min(a, b), std::max(a, b)};
    };
    for (std::size_t i = 0; i < map.feature_edges.size(); ++i) {
      const auto p = where(map.feature_edges[i][0]), q = where(map.feature_edges[i][1]);
      bool ok = false;
      if (p.first >= 0 && q.first >= 0) {
        if (p.second >= 0 && q.second >= 0)
          ok = p == q;
        else if (p.second >= 0)
          ok = q.first == p.first || q.first == p.second;
        else if (q.second >= 0)
          ok = p.first == q.first || p.first == q.second;
        else
          ok = edges.count({std::min(p.first, q.first), std::max(p.first, q.first)}) > 0 ||
               through_split_point(map.feature_edges[i][0], map.feature_edges[i][1], p.first,
                                   q.first);
      }
      if (!ok && p.first >= 0 && q.first >= 0) {
        // The input refined the feature edge (the shape refinement bisects feature edges, and
        // the coarsening may keep a bisection point): a or b inside a boundary edge whose end is
        // such a point, on the segment and no input vertex's image, and from there a path as
        // above.
        const int va = map.feature_edges[i][0], vb = map.feature_edges[i][1];
        auto split_point = [&](int m) { return !images.count(m) && on_input_segment(va, vb, m); };
        auto ends = [&](const std::pair<int, int>& w) {
          std::vector<int> out;
          if (w.second < 0) {
            out.push_back(w.first);
          } else {
            for (int m : {w.first, w.second})
              if (split_point(m)) out.push_back(m);
          }
          return out;
        };
        for (int x : ends(p))
          for (int y : ends(q))
            ok = ok || x == y || edges.count({std::min(x, y), std::max(x, y)}) > 0 ||
                 through_split_point(va, vb, x, y);
      }
      if (!ok) {
        ++r.features_off_edges;
        if (r.first_feature_off < 0) r.first_feature_off = int(i);
      }
    }
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace curvefem::meshing::curved
