#include "meshing/check/check_surface.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numeric>
#include <sstream>
#include <tuple>
#include <utility>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/position_key.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::check {
namespace {

// A face corner k seen as the directed edge F(f,k) → F(f,k+1), stored undirected.
struct HalfEdge {
  int lo, hi;    // vertex ids, lo < hi
  int face;      // face id
  bool forward;  // traversed lo → hi
};

// Undirected edge = a run [begin, begin + count) of half-edges sorted by (lo, hi, face).
struct Edge {
  int lo, hi;
  int begin, count;
};

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : m_parent(n) {
    std::iota(m_parent.begin(), m_parent.end(), 0);
  }
  int find(int x) {
    while (m_parent[x] != x) x = m_parent[x] = m_parent[m_parent[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) m_parent[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<int> m_parent;
};

struct Topology {
  std::vector<HalfEdge> half_edges;  // sorted
  std::vector<Edge> edges;           // sorted by (lo, hi)
  std::vector<int> face_edge;        // 3·#F: edge of corner k of face f, -1 for a self-loop
};

Topology build_topology(const Eigen::MatrixXi& F) {
  Topology t;
  const int nf = static_cast<int>(F.rows());
  t.half_edges.reserve(3 * static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a != b) t.half_edges.push_back({std::min(a, b), std::max(a, b), f, a < b});
    }
  }
  std::sort(t.half_edges.begin(), t.half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.lo, x.hi, x.face, x.forward) < std::tie(y.lo, y.hi, y.face, y.forward);
  });
  t.face_edge.assign(3 * static_cast<std::size_t>(nf), -1);
  const int nh = static_cast<int>(t.half_edges.size());
  for (int i = 0; i < nh;) {
    int j = i;
    while (j < nh && t.half_edges[j].lo == t.half_edges[i].lo &&
           t.half_edges[j].hi == t.half_edges[i].hi)
      ++j;
    t.edges.push_back({t.half_edges[i].lo, t.half_edges[i].hi, i, j - i});
    i = j;
  }
  // Corner → edge: binary search of (lo, hi) in the sorted edge list.
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a == b) continue;
      const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
      const auto it = std::lower_bound(t.edges.begin(), t.edges.end(), key,
                                       [](const Edge& e, const std::pair<int, int>& k2) {
                                         return std::pair<int, int>{e.lo, e.hi} < k2;
                                       });
      t.face_edge[3 * f + k] = static_cast<int>(it - t.edges.begin());
    }
  }
  return t;
}

// Vertex → incident faces (each face once), in increasing face order.
struct VertexFaces {
  std::vector<int> offsets, faces;
  int count(int v) const { return offsets[v + 1] - offsets[v]; }
};

VertexFaces build_vertex_faces(const Eigen::MatrixXi& F, int nv) {
  VertexFaces vf;
  vf.offsets.assign(static_cast<std::size_t>(nv) + 1, 0);
  auto distinct_corners = [&](int f, auto&& visit) {
    for (int k = 0; k < 3; ++k) {
      const int v = F(f, k);
      if ((k > 0 && F(f, 0) == v) || (k > 1 && F(f, 1) == v)) continue;
      visit(v);
    }
  };
  for (int f = 0; f < F.rows(); ++f) distinct_corners(f, [&](int v) { ++vf.offsets[v + 1]; });
  for (int v = 0; v < nv; ++v) vf.offsets[v + 1] += vf.offsets[v];
  vf.faces.resize(static_cast<std::size_t>(vf.offsets[nv]));
  std::vector<int> fill(vf.offsets.begin(), vf.offsets.end() - 1);
  for (int f = 0; f < F.rows(); ++f) distinct_corners(f, [&](int v) { vf.faces[fill[v]++] = f; });
  return vf;
}

// True when the faces around v do not form one fan: faces are linked through the edges at v that
// have two or more faces (a non-manifold edge links all its faces, so that an edge defect is not
// reported a second time at its end vertices).
bool is_pinched(int v, const Eigen::MatrixXi& F, const Topology& t, const VertexFaces& vf,
                std::vector<int>& local_parent) {
  const int begin = vf.offsets[v], n = vf.count(v);
  if (n <= 1) return false;
  const auto first = vf.faces.begin() + begin, last = first + n;
  local_parent.resize(n);
  std::iota(local_parent.begin(), local_parent.end(), 0);
  auto find = [&](int x) {
    while (local_parent[x] != x) x = local_parent[x] = local_parent[local_parent[x]];
    return x;
  };
  int groups = n;
  for (int i = 0; i < n; ++i) {
    const int f = first[i];
    for (int k = 0; k < 3; ++k) {
      if (F(f, k) != v && F(f, (k + 1) % 3) != v) continue;
      const int e = t.face_edge[3 * f + k];
      if (e < 0 || t.edges[e].count < 2) continue;
      for (int h = 0; h < t.edges[e].count; ++h) {
        const int g = t.half_edges[t.edges[e].begin + h].face;
        const int j = static_cast<int>(std::lower_bound(first, last, g) - first);
        const int a = find(i), b = find(j);
        if (a != b) {
          local_parent[std::max(a, b)] = std::min(a, b);
          --groups;
        }
      }
    }
  }
  return groups > 1;
}

std::string join_ids(const std::vector<long long>& ids, long long count, int per_item,
                     const char* sep_in_item) {
  std::ostringstream s;
  const std::size_t items = ids.size() / per_item;
  for (std::size_t i = 0; i < items; ++i) {
    if (i) s << ", ";
    for (int k = 0; k < per_item; ++k) s << (k ? sep_in_item : "") << ids[i * per_item + k];
  }
  if (static_cast<long long>(items) < count) s << ", ...";
  return s.str();
}

Defect make_defect(std::string kind, long long count, std::string id_kind,
                   std::vector<long long> ids, const std::string& what) {
  Defect d;
  d.kind = std::move(kind);
  d.count = count;
  d.id_kind = std::move(id_kind);
  d.ids = std::move(ids);
  const int per_item = (d.id_kind == "edge" || d.id_kind == "face_pair") ? 2 : 1;
  const char* sep = d.id_kind == "edge" ? "-" : "/";
  d.message = std::to_string(count) + " " + what;
  if (!d.ids.empty()) d.message += ": " + join_ids(d.ids, count, per_item, sep);
  return d;
}

std::string format_g(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

// Minimum and maximum corner angle (degrees) over faces whose edges all have positive length.
std::pair<double, double> angle_range(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  double lo = 180.0, hi = 0.0;
  bool any = false;
  for (int f = 0; f < F.rows(); ++f) {
    std::array<Eigen::Vector3d, 3> p;
    for (int k = 0; k < 3; ++k) p[k] = V.row(F(f, k)).transpose();
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d u = p[(k + 1) % 3] - p[k], w = p[(k + 2) % 3] - p[k];
      if (u.squaredNorm() == 0.0 || w.squaredNorm() == 0.0) continue;
      const double a = std::atan2(u.cross(w).norm(), u.dot(w)) * 180.0 / M_PI;
      lo = std::min(lo, a);
      hi = std::max(hi, a);
      any = true;
    }
  }
  return any ? std::pair{lo, hi} : std::pair{0.0, 0.0};
}

// A warning of `kind` over `items` (id lists with their angle, worst first): the count, the
// listed ids and the worst item's angle and position.
struct Flagged {
  std::vector<long long> ids;  // one id (face) or two (edge: its vertices)
  double angle = 0;            // degrees
  Eigen::Vector3d at;
};
Defect make_warning(std::string kind, std::vector<Flagged> items, std::size_t max_ids,
                    const std::string& id_kind, const std::string& what,
                    const std::string& angle_what, bool worst_is_largest) {
  std::stable_sort(items.begin(), items.end(), [&](const Flagged& a, const Flagged& b) {
    return worst_is_largest ? a.angle > b.angle : a.angle < b.angle;
  });
  std::vector<long long> ids;
  for (std::size_t i = 0; i < items.size() && i < max_ids; ++i)
    ids.insert(ids.end(), items[i].ids.begin(), items[i].ids.end());
  Defect d = make_defect(std::move(kind), static_cast<long long>(items.size()), id_kind,
                         std::move(ids), what);
  const Flagged& w = items.front();
  d.message += "; worst " + angle_what + " " + format_g(w.angle) + " deg at (" + format_g(w.at[0]) +
               ", " + format_g(w.at[1]) + ", " + format_g(w.at[2]) + ")";
  return d;
}

// Unit normal of face f, zero for a face of zero area.
Eigen::Vector3d unit_normal(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int f) {
  const Eigen::Vector3d p0 = V.row(F(f, 0)).transpose(), p1 = V.row(F(f, 1)).transpose(),
                        p2 = V.row(F(f, 2)).transpose();
  const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
  return n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
}

double angle_between_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

std::vector<std::pair<int, double>> needle_faces_of(const Eigen::MatrixXd& V,
                                                    const Eigen::MatrixXi& F,
                                                    const std::vector<char>& degenerate,
                                                    double angle) {
  std::vector<std::pair<int, double>> out;
  for (int f = 0; f < F.rows(); ++f) {
    if (degenerate[f]) continue;
    double smallest = 180.0;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = V.row(F(f, k)).transpose();
      smallest = std::min(smallest, angle_between_deg(V.row(F(f, (k + 1) % 3)).transpose() - p,
                                                      V.row(F(f, (k + 2) % 3)).transpose() - p));
    }
    if (smallest < angle) out.emplace_back(f, smallest);
  }
  return out;
}

std::vector<FoldEdge> near_fold_edges_of(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                         const Topology& t, double angle) {
  std::vector<FoldEdge> out;
  for (const Edge& e : t.edges) {
    if (e.count != 2) continue;
    const HalfEdge& a = t.half_edges[e.begin];
    const HalfEdge& b = t.half_edges[e.begin + 1];
    if (a.forward == b.forward) continue;
    const Eigen::Vector3d na = unit_normal(V, F, a.face), nb = unit_normal(V, F, b.face);
    if (na.isZero() || nb.isZero()) continue;
    const double turn = angle_between_deg(na, nb);
    if (turn > angle) out.push_back({e.lo, e.hi, turn});
  }
  return out;
}

// Referenced vertices whose coordinates equal (==) those of a lower referenced id. Compared as
// values: -0.0 equals 0.0 (same point), otherwise this is bit equality (readers reject NaN).
std::vector<int> duplicate_vertices(const Eigen::MatrixXd& V, const std::vector<char>& referenced) {
  std::vector<std::pair<PositionKey, int>> keys;
  for (int v = 0; v < V.rows(); ++v)
    if (referenced[v]) keys.push_back({position_key(V.row(v)), v});
  std::sort(keys.begin(), keys.end());
  std::vector<int> dups;
  for (std::size_t i = 1; i < keys.size(); ++i)
    if (keys[i].first == keys[i - 1].first) dups.push_back(keys[i].second);
  std::sort(dups.begin(), dups.end());
  return dups;
}

// Faces with the same vertex set as a face of lower id.
std::vector<int> duplicate_faces(const Eigen::MatrixXi& F) {
  std::vector<std::pair<std::array<int, 3>, int>> keys(static_cast<std::size_t>(F.rows()));
  for (int f = 0; f < F.rows(); ++f) {
    std::array<int, 3> k{F(f, 0), F(f, 1), F(f, 2)};
    std::sort(k.begin(), k.end());
    keys[f] = {k, f};
  }
  std::sort(keys.begin(), keys.end());
  std::vector<int> dups;
  for (std::size_t i = 1; i < keys.size(); ++i)
    if (keys[i].first == keys[i - 1].first) dups.push_back(keys[i].second);
  std::sort(dups.begin(), dups.end());
  return dups;
}

}  // namespace

std::vector<std::pair<int, double>> needle_faces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                                 double angle_deg) {
  return needle_faces_of(V, F, exactly_degenerate_faces(V, F), angle_deg);
}

std::vector<FoldEdge> near_fold_edges(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                      double angle_deg) {
  return near_fold_edges_of(V, F, build_topology(F), angle_deg);
}

CheckReport check_surface(const SurfaceMesh& mesh, const CheckOptions& options,
                          const ProgressFn& progress) {
  const Stopwatch watch;
  const Eigen::MatrixXd& V = mesh.V;
  const Eigen::MatrixXi& F = mesh.F;
  CF_VERIFY(V.cols() == 3 || V.rows() == 0, "V must be #V x 3");
  CF_VERIFY(F.cols() == 3 || F.rows() == 0, "F must be #F x 3 (triangles)");
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= nv) {
        ErrorContext where;
        where.face = f;
        throw InputError("vertex index " + std::to_string(F(f, k)) + " out of range [0, " +
                             std::to_string(nv) + ")",
                         where);
      }
  const std::size_t max_ids = static_cast<std::size_t>(std::max(options.max_listed_ids, 0));

  CheckReport r;
  r.vertices = nv;
  r.faces = nf;
  r.bbox_longest_edge = bbox_longest_edge(V);
  if (nf == 0) {
    r.unreferenced_vertices = nv;
    r.defects.push_back(make_defect("empty", 0, "face", {}, "faces (surface is empty)"));
    r.time_s = watch.seconds();
    return r;
  }

  ProgressTicker ticker(progress, "check topology", 6);
  std::vector<char> referenced(static_cast<std::size_t>(nv), 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) referenced[F(f, k)] = 1;
  r.referenced_vertices = std::count(referenced.begin(), referenced.end(), 1);
  r.unreferenced_vertices = nv - r.referenced_vertices;

  // Edges: boundary, non-manifold, inconsistently oriented.
  const Topology t = build_topology(F);
  ticker.tick(1);
  std::vector<long long> boundary_ids, non_manifold_ids, inconsistent_ids;
  auto list_edge = [&](std::vector<long long>& ids, const Edge& e) {
    if (ids.size() < 2 * max_ids) {
      ids.push_back(e.lo);
      ids.push_back(e.hi);
    }
  };
  for (const Edge& e : t.edges) {
    if (e.count == 1) {
      ++r.boundary_edges;
      list_edge(boundary_ids, e);
    } else if (e.count > 2) {
      ++r.non_manifold_edges;
      list_edge(non_manifold_ids, e);
    } else if (t.half_edges[e.begin].forward == t.half_edges[e.begin + 1].forward) {
      ++r.inconsistent_edges;
      list_edge(inconsistent_ids, e);
    }
  }
  r.closed = r.boundary_edges == 0;
  r.edge_manifold = r.non_manifold_edges == 0;
  r.consistently_oriented = r.inconsistent_edges == 0;
  ticker.tick(2);

  // Vertices: pinches (several fans around one vertex).
  const VertexFaces vf = build_vertex_faces(F, nv);
  std::vector<long long> pinch_ids;
  {
    std::vector<int> scratch;
    for (int v = 0; v < nv; ++v) {
      if (!is_pinched(v, F, t, vf, scratch)) continue;
      ++r.non_manifold_vertices;
      if (pinch_ids.size() < max_ids) pinch_ids.push_back(v);
    }
  }
  r.vertex_manifold = r.non_manifold_vertices == 0;
  ticker.tick(3);

  // Components (faces linked through edges) and orientability (parity propagation through the
  // manifold edges; an inconsistent edge flips the parity).
  UnionFind components(static_cast<std::size_t>(nf));
  for (const Edge& e : t.edges)
    for (int h = 1; h < e.count; ++h)
      components.unite(t.half_edges[e.begin].face, t.half_edges[e.begin + h].face);
  std::vector<int> component_of(static_cast<std::size_t>(nf));
  {
    std::vector<int> id_of_root(static_cast<std::size_t>(nf), -1);
    for (int f = 0; f < nf; ++f) {
      int& id = id_of_root[components.find(f)];
      if (id < 0) id = static_cast<int>(r.components++);
      component_of[f] = id;
    }
  }
  {
    std::vector<signed char> parity(static_cast<std::size_t>(nf), -1);
    std::vector<int> stack;
    r.orientable = true;
    for (int seed = 0; seed < nf; ++seed) {
      if (parity[seed] >= 0) continue;
      long long size = 0, flipped = 0;
      bool ok = true;
      parity[seed] = 0;
      stack.push_back(seed);
      while (!stack.empty()) {
        const int f = stack.back();
        stack.pop_back();
        ++size;
        flipped += parity[f];
        for (int k = 0; k < 3; ++k) {
          const int e = t.face_edge[3 * f + k];
          if (e < 0 || t.edges[e].count != 2) continue;
          const HalfEdge& a = t.half_edges[t.edges[e].begin];
          const HalfEdge& b = t.half_edges[t.edges[e].begin + 1];
          if (a.face == b.face) continue;
          const int g = a.face == f ? b.face : a.face;
          const signed char want = static_cast<signed char>(parity[f] ^ (a.forward == b.forward));
          if (parity[g] < 0) {
            parity[g] = want;
            stack.push_back(g);
          } else if (parity[g] != want) {
            ok = false;
          }
        }
      }
      if (ok)
        r.faces_to_flip += std::min(flipped, size - flipped);
      else
        r.orientable = false;
    }
  }
  ticker.tick(4);

  // Euler characteristic and genus (closed orientable 2-manifold: genus = Σ_c (2 − χ_c) / 2).
  r.euler_characteristic = r.referenced_vertices - static_cast<long long>(t.edges.size()) + nf;
  if (r.closed && r.edge_manifold && r.vertex_manifold && r.orientable) {
    std::vector<long long> chi(static_cast<std::size_t>(r.components), 0);
    for (int f = 0; f < nf; ++f) ++chi[component_of[f]];
    for (const Edge& e : t.edges) --chi[component_of[t.half_edges[e.begin].face]];
    for (int v = 0; v < nv; ++v)
      if (vf.count(v) > 0) ++chi[component_of[vf.faces[vf.offsets[v]]]];
    r.genus = 0;
    for (const long long c : chi) {
      if ((2 - c) % 2 != 0 || c > 2) {
        r.genus = -1;
        break;
      }
      r.genus += (2 - c) / 2;
    }
  }

  // Volume and orientation.
  r.signed_volume = signed_volume(mesh);
  if (r.closed && r.edge_manifold && r.consistently_oriented)
    r.orientation_sign = (r.signed_volume > 0.0) - (r.signed_volume < 0.0);

  // Faces: exact degeneracy, angles, duplicates.
  const std::vector<char> degenerate = exactly_degenerate_faces(V, F);
  std::vector<long long> degenerate_ids;
  for (int f = 0; f < nf; ++f) {
    if (!degenerate[f]) continue;
    ++r.degenerate_faces;
    if (degenerate_ids.size() < max_ids) degenerate_ids.push_back(f);
  }
  std::tie(r.min_angle_deg, r.max_angle_deg) = angle_range(V, F);
  // Warnings: needle faces and near folds (CheckReport::warnings).
  std::vector<Flagged> needles, folds;
  for (const auto& [f, angle] : needle_faces_of(V, F, degenerate, options.needle_angle_deg))
    needles.push_back(
        {{f}, angle, (V.row(F(f, 0)) + V.row(F(f, 1)) + V.row(F(f, 2))).transpose() / 3.0});
  for (const FoldEdge& e : near_fold_edges_of(V, F, t, options.fold_angle_deg))
    folds.push_back({{e.lo, e.hi}, e.turn_deg, 0.5 * (V.row(e.lo) + V.row(e.hi)).transpose()});
  if (!needles.empty())
    r.warnings.push_back(
        make_warning("needle", std::move(needles), max_ids, "face",
                     "needle faces (a corner angle below " + format_g(options.needle_angle_deg) +
                         " deg: where the coarse surface keeps one, the tet on it is as flat; "
                         "`curvefem check IN --merge-short-edges L -o OUT` merges the edges "
                         "shorter than L)",
                     "corner angle", /*worst_is_largest=*/false));
  if (!folds.empty())
    r.warnings.push_back(make_warning("near_fold", std::move(folds), max_ids, "edge",
                                      "near folds (edges whose face normals turn by more than " +
                                          format_g(options.fold_angle_deg) +
                                          " deg: the surface doubles back on itself, and the shell "
                                          "and the tets there are as thin)",
                                      "normal turn", /*worst_is_largest=*/true));
  r.duplicate_vertices = static_cast<long long>(duplicate_vertices(V, referenced).size());
  r.duplicate_faces = static_cast<long long>(duplicate_faces(F).size());
  ticker.tick(5);
  ticker.finish();
  const double topology_s = watch.seconds();

  // Self-intersections.
  std::vector<long long> pair_ids;
  if (options.self_intersections) {
    ProgressTicker si_ticker(progress, "check self-intersections", 1);
    const bool oriented_manifold = r.edge_manifold && r.vertex_manifold && r.consistently_oriented;
    bool repeated_index = false;
    for (int f = 0; f < nf && !repeated_index; ++f)
      repeated_index = F(f, 0) == F(f, 1) || F(f, 1) == F(f, 2) || F(f, 2) == F(f, 0);
    const SelfIntersectionResult si =
        find_self_intersections(V, F, degenerate, oriented_manifold && !repeated_index);
    r.self_intersections_checked = true;
    r.self_intersections_mesh_api = si.used_mesh_api;
    r.self_intersecting_pairs = static_cast<long long>(si.pairs.size());
    for (std::size_t i = 0; i < si.pairs.size() && i < max_ids; ++i) {
      pair_ids.push_back(si.pairs[i].first);
      pair_ids.push_back(si.pairs[i].second);
    }
    si_ticker.finish();
  }

  r.volume_bounded = r.closed && r.edge_manifold && r.vertex_manifold && r.consistently_oriented &&
                     r.self_intersections_checked && r.self_intersecting_pairs == 0;

  // Defects, in pipeline order.
  if (r.boundary_edges > 0)
    r.defects.push_back(make_defect("open", r.boundary_edges, "edge", boundary_ids,
                                    "boundary edges (surface is open)"));
  if (r.non_manifold_edges > 0)
    r.defects.push_back(make_defect("non_manifold_edge", r.non_manifold_edges, "edge",
                                    non_manifold_ids, "non-manifold edges (more than two faces)"));
  if (r.non_manifold_vertices > 0)
    r.defects.push_back(make_defect("non_manifold_vertex", r.non_manifold_vertices, "vertex",
                                    pinch_ids,
                                    "non-manifold vertices (faces around them form several fans)"));
  if (r.inconsistent_edges > 0) {
    Defect d = make_defect("orientation", r.inconsistent_edges, "edge", inconsistent_ids,
                           "inconsistently oriented edges (both faces traverse them in the same "
                           "direction)");
    d.message += r.orientable ? "; orientable: flip " + std::to_string(r.faces_to_flip) + " faces"
                              : "; not orientable";
    r.defects.push_back(std::move(d));
  }
  if (r.orientation_sign <= 0 && r.closed && r.edge_manifold && r.consistently_oriented) {
    Defect d;
    d.kind = "inward";
    d.count = r.faces;
    d.id_kind = "face";
    d.message = r.orientation_sign < 0
                    ? "closed and consistently oriented but inward (signed volume " +
                          format_g(r.signed_volume) + "): flip all faces"
                    : "closed and consistently oriented but encloses no volume (signed volume " +
                          format_g(r.signed_volume) + ")";
    r.defects.push_back(std::move(d));
  }
  if (r.degenerate_faces > 0)
    r.defects.push_back(make_defect("degenerate", r.degenerate_faces, "face", degenerate_ids,
                                    "degenerate faces (repeated vertex or exactly collinear "
                                    "corners)"));
  if (r.self_intersecting_pairs > 0)
    r.defects.push_back(make_defect("self_intersection", r.self_intersecting_pairs, "face_pair",
                                    pair_ids, "self-intersecting face pairs"));

  r.acceptable = r.defects.empty();
  r.time_s = watch.seconds();
  log::info("check: ", nf, " faces, ", r.components, " components, genus ", r.genus, ", ",
            r.defects.size(), " defect classes, ", r.warnings.size(), " warning classes, ",
            r.self_intersecting_pairs, " self-intersecting pairs",
            r.self_intersections_checked ? "" : " (not checked)", " in ", format_g(r.time_s),
            " s (topology and faces ", format_g(topology_s), " s, self-intersections ",
            format_g(r.time_s - topology_s), " s, ",
            r.self_intersections_mesh_api ? "PMP mesh" : "soup", ")");
  return r;
}

}  // namespace curvefem::check
