#include "meshing/shell/thin_refine.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <queue>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {
namespace {

// 2-D MIPS energy of a triangle (2 for the equilateral one; +inf when flat).
double triangle_mips(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double area2 = (b - a).cross(c - a).norm();
  const double sum = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return area2 > 0 ? sum / (std::sqrt(3.0) * area2) : HUGE_VAL;
}

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

struct Refiner {
  const SurfaceMesh& input;
  const InputSurfaceIndex index;
  std::vector<Eigen::Vector3d> V;
  std::vector<std::array<int, 3>> F;
  std::vector<int> parent;
  std::vector<Eigen::Matrix3d> W;  // column k: corner k in the parent face
  std::unordered_map<std::uint64_t, std::vector<int>> edge_faces;

  explicit Refiner(const SurfaceMesh& in) : input(in), index(in.V, in.F) {}

  Eigen::Vector3d area_normal(int f) const {
    const auto& t = F[std::size_t(f)];
    return (V[std::size_t(t[1])] - V[std::size_t(t[0])])
        .cross(V[std::size_t(t[2])] - V[std::size_t(t[0])]);
  }

  double thickness(const Eigen::Vector3d& x, const Eigen::Vector3d& n,
                   const std::vector<int>& ignore) const {
    if (!(n.norm() > 0)) return HUGE_VAL;
    return index.ray_distance(x, -n.normalized(), ignore);
  }

  // Thickness at the point x of edge (a, b) (faces fs): along the inward mean of the two faces'
  // normals, beyond their input faces.
  double edge_thickness(const Eigen::Vector3d& x, const std::array<int, 2>& fs) const {
    std::vector<int> ignore{parent[std::size_t(fs[0])], parent[std::size_t(fs[1])]};
    if (ignore[0] == ignore[1]) ignore.pop_back();
    std::sort(ignore.begin(), ignore.end());
    return thickness(x, area_normal(fs[0]).normalized() + area_normal(fs[1]).normalized(), ignore);
  }
  // |ab| / the thickness at the midpoint of (a, b) (cached per edge: the surface never moves).
  double ratio(int a, int b) {
    const std::uint64_t key = edge_key(a, b);
    auto it = mid_thickness.find(key);
    if (it == mid_thickness.end()) {
      const Eigen::Vector3d m = 0.5 * (V[std::size_t(a)] + V[std::size_t(b)]);
      it = mid_thickness.emplace(key, edge_thickness(m, faces_of(a, b))).first;
    }
    const double len = (V[std::size_t(a)] - V[std::size_t(b)]).norm();
    return it->second > 0 ? len / it->second : HUGE_VAL;
  }
  std::unordered_map<std::uint64_t, double> mid_thickness;

  void add_face(int f) {
    for (int c = 0; c < 3; ++c)
      edge_faces[edge_key(F[std::size_t(f)][std::size_t(c)],
                          F[std::size_t(f)][std::size_t((c + 1) % 3)])]
          .push_back(f);
  }
  void remove_face(int f) {
    for (int c = 0; c < 3; ++c) {
      auto& list = edge_faces[edge_key(F[std::size_t(f)][std::size_t(c)],
                                       F[std::size_t(f)][std::size_t((c + 1) % 3)])];
      list.erase(std::find(list.begin(), list.end(), f));
    }
  }

  // The two faces of edge (a, b) (InputError on a non-manifold edge).
  std::array<int, 2> faces_of(int a, int b) const {
    const auto it = edge_faces.find(edge_key(a, b));
    if (it == edge_faces.end() || it->second.size() != 2)
      throw InputError("thin refinement: input edge (" + std::to_string(a) + ", " +
                       std::to_string(b) + ") does not have exactly two faces");
    return {it->second[0], it->second[1]};
  }

  // Bisects (a, b) at its midpoint; the new faces replace fs and follow.
  void split(int a, int b, const std::array<int, 2>& fs, std::vector<int>& touched) {
    const int m = int(V.size());
    V.push_back(0.5 * (V[std::size_t(a)] + V[std::size_t(b)]));
    for (int f : fs) {
      remove_face(f);
      const auto t = F[std::size_t(f)];
      int i = 0;
      while (!((t[std::size_t(i)] == a && t[std::size_t((i + 1) % 3)] == b) ||
               (t[std::size_t(i)] == b && t[std::size_t((i + 1) % 3)] == a)))
        ++i;
      const int p = t[std::size_t(i)], q = t[std::size_t((i + 1) % 3)],
                r = t[std::size_t((i + 2) % 3)];
      const Eigen::Matrix3d w = W[std::size_t(f)];
      const Eigen::Vector3d wp = w.col(i), wq = w.col((i + 1) % 3), wr = w.col((i + 2) % 3),
                            wm = 0.5 * (wp + wq);
      const int g = int(F.size());
      F[std::size_t(f)] = {p, m, r};
      W[std::size_t(f)] << wp, wm, wr;
      F.push_back({m, q, r});
      Eigen::Matrix3d wg;
      wg << wm, wq, wr;
      W.push_back(wg);
      parent.push_back(parent[std::size_t(f)]);
      add_face(f);
      add_face(g);
      touched.push_back(f);
      touched.push_back(g);
    }
  }

  // The end of the longest-edge path from edge e: while a face of the current edge has a longer
  // edge (relative tolerance 1e-12: ties count as longest), step to that edge; stop there when
  // it is kept (kept_end: the edge before it is returned) or after 64 steps.
  struct Closure {
    std::array<int, 2> edge;
    bool kept_end = false;
  };
  Closure closure(std::array<int, 2> e, const std::set<std::uint64_t>& kept) const {
    for (int step = 0; step < 64; ++step) {
      const double len = (V[std::size_t(e[0])] - V[std::size_t(e[1])]).norm();
      std::array<int, 2> next{};
      double next_len = len * (1 + 1e-12);
      for (int f : faces_of(e[0], e[1])) {
        const auto [l, l_len] = longest(f);
        if (l_len > next_len) next = l, next_len = l_len;
      }
      if (next_len <= len * (1 + 1e-12)) return {e, false};
      if (kept.count(edge_key(next[0], next[1]))) return {e, true};
      e = next;
    }
    return {e, false};
  }

  // Without the closure: e itself, with kept_end where a face of e has a longer kept edge.
  Closure closure_off(std::array<int, 2> e, const std::set<std::uint64_t>& kept) const {
    const double len = (V[std::size_t(e[0])] - V[std::size_t(e[1])]).norm();
    for (int f : faces_of(e[0], e[1])) {
      const auto [l, l_len] = longest(f);
      if (l_len > len * (1 + 1e-12) && kept.count(edge_key(l[0], l[1]))) return {e, true};
    }
    return {e, false};
  }

  // Whether bisecting (a, b) keeps the shape of its two faces along kept edges: a face whose
  // longest edge is a kept one (never bisected) gives the child along it half its height over
  // it, and repeated splits of the face's other edges (thin, next to a CAD edge, where the
  // thickness stays small) leave slivers of any aspect along it (shape_occt at ratio 3: a refined
  // face 90 long and 1.6e-4 high along a CAD edge, kept by the coarse surface; min scaled
  // Jacobian 2.5e-7). That child must then have a 2-D MIPS of at most max(bound, its parent's).
  // Elsewhere nothing is checked: a longest edge that is thin is bisected in turn (longest-edge
  // refinement: a tube's needle strips), and one that is not (a plate's rim strip) is halved
  // only as often as the thin edges next to it, a few times.
  bool children_shaped(int a, int b, const std::array<int, 2>& fs, double bound,
                       const std::set<std::uint64_t>& kept) {
    const Eigen::Vector3d A = V[std::size_t(a)], B = V[std::size_t(b)], m = 0.5 * (A + B);
    for (int f : fs) {
      const auto& t = F[std::size_t(f)];
      int r = 0;
      while (t[std::size_t(r)] == a || t[std::size_t(r)] == b) ++r;
      const int c = t[std::size_t(r)];
      const Eigen::Vector3d R = V[std::size_t(c)];
      const auto [p, q] = longest(f).first;
      const std::uint64_t key = edge_key(p, q);
      if (key == edge_key(a, b) || !kept.count(key)) continue;
      // The longest edge is (a, c) or (b, c); its child is (a, m, c) or (m, b, c).
      const double child = (p == a || q == a) ? triangle_mips(A, m, R) : triangle_mips(m, B, R);
      if (child > std::max(bound, triangle_mips(A, B, R))) return false;
    }
    return true;
  }

  // Longest edge of face f as (a, b), and the face's worst thin ratio.
  std::pair<std::array<int, 2>, double> longest(int f) const {
    const auto& t = F[std::size_t(f)];
    std::array<int, 2> best{};
    double best_len = -1;
    for (int c = 0; c < 3; ++c) {
      const int a = t[std::size_t(c)], b = t[std::size_t((c + 1) % 3)];
      const double len = (V[std::size_t(a)] - V[std::size_t(b)]).squaredNorm();
      if (len > best_len) best_len = len, best = {a, b};
    }
    return {best, std::sqrt(best_len)};
  }
  double worst_ratio(int f) {
    const auto& t = F[std::size_t(f)];
    double r = 0;
    for (int c = 0; c < 3; ++c)
      r = std::max(r, ratio(t[std::size_t(c)], t[std::size_t((c + 1) % 3)]));
    return r;
  }

  // The input as the starting surface: identity parents.
  void init() {
    const int nv = input.num_vertices(), nf = input.num_faces();
    V.resize(std::size_t(nv));
    for (int v = 0; v < nv; ++v) V[std::size_t(v)] = input.V.row(v).transpose();
    F.resize(std::size_t(nf));
    parent.resize(std::size_t(nf));
    W.assign(std::size_t(nf), Eigen::Matrix3d::Identity());
    for (int f = 0; f < nf; ++f) {
      for (int c = 0; c < 3; ++c) F[std::size_t(f)][std::size_t(c)] = input.F(f, c);
      parent[std::size_t(f)] = f;
      add_face(f);
    }
  }

  // The refined surface into `out` (tags follow the parent); returns the input faces refined.
  int write(BeveledSurface& out) const {
    const int n = int(F.size()), nf = input.num_faces();
    out.mesh.V.resize(Eigen::Index(V.size()), 3);
    for (std::size_t v = 0; v < V.size(); ++v) out.mesh.V.row(Eigen::Index(v)) = V[v];
    out.mesh.F.resize(n, 3);
    if (input.has_tags()) out.mesh.tags.resize(n);
    std::vector<int> children(std::size_t(nf), 0);
    for (int f = 0; f < n; ++f) {
      for (int c = 0; c < 3; ++c) out.mesh.F(f, c) = F[std::size_t(f)][std::size_t(c)];
      if (input.has_tags()) out.mesh.tags[f] = input.tags[parent[std::size_t(f)]];
      ++children[std::size_t(parent[std::size_t(f)])];
    }
    out.face_parent = parent;
    out.corner_bary = W;
    out.beveled_faces =
        int(std::count_if(children.begin(), children.end(), [](int c) { return c > 1; }));
    return out.beveled_faces;
  }

  void count(double limit, int& thin, double& worst) {
    thin = 0;
    worst = 0;
    std::vector<std::uint64_t> keys;
    for (const auto& [key, faces] : edge_faces)
      if (!faces.empty() && !mid_thickness.count(key)) keys.push_back(key);
    std::vector<double> t(keys.size());
    tbb::parallel_for(std::size_t(0), keys.size(), [&](std::size_t i) {
      const int a = int(keys[i] >> 32), b = int(keys[i] & 0xffffffffu);
      t[i] = edge_thickness(0.5 * (V[std::size_t(a)] + V[std::size_t(b)]), faces_of(a, b));
    });
    for (std::size_t i = 0; i < keys.size(); ++i) mid_thickness[keys[i]] = t[i];
    for (const auto& [key, faces] : edge_faces) {
      if (faces.empty()) continue;
      const int a = int(key >> 32), b = int(key & 0xffffffffu);
      const double r = ratio(a, b);
      if (r > limit) ++thin;
      if (std::isfinite(r)) worst = std::max(worst, r);
    }
  }
};

}  // namespace

BeveledSurface refine_thin_parts(const SurfaceMesh& input, const ThinRefineOptions& options,
                                 ThinRefineStats& stats) {
  Stopwatch watch;
  stats = {};
  const int nf = input.num_faces();
  BeveledSurface out = unbeveled_surface(input, ExtrusionDirections{});
  if (!(options.max_edge_per_thickness > 0) || nf == 0) return out;
  Refiner r(input);
  r.init();
  const double limit = options.max_edge_per_thickness;
  std::set<std::uint64_t> kept;
  for (const auto& e : options.kept_edges) kept.insert(edge_key(e[0], e[1]));
  r.count(limit, stats.thin_edges_before, stats.max_ratio_before);

  for (int round = 0; round < options.max_rounds && stats.thin_edges_before > 0; ++round) {
    std::vector<std::pair<double, int>> order;  // (-longest edge, face)
    for (int f = 0; f < int(r.F.size()); ++f)
      if (r.worst_ratio(f) > limit) order.emplace_back(-r.longest(f).second, f);
    std::sort(order.begin(), order.end());
    std::vector<char> touched_now(r.F.size() + 2 * order.size() + 2, 0);
    int splits = 0;
    for (const auto& [neg_len, f] : order) {
      if (touched_now[std::size_t(f)]) continue;
      if (int(r.F.size()) + 2 > nf + options.max_added_faces) {
        stats.budget_reached = true;
        break;
      }
      const auto [e, len] = r.longest(f);
      const double before = r.ratio(e[0], e[1]);
      if (!(before > limit) || kept.count(edge_key(e[0], e[1]))) continue;
      const auto fs = r.faces_of(e[0], e[1]);
      if (touched_now[std::size_t(fs[0])] || touched_now[std::size_t(fs[1])]) continue;
      // The halves' ratios, at their own midpoints (cached for when they exist).
      const Eigen::Vector3d A = r.V[std::size_t(e[0])], B = r.V[std::size_t(e[1])];
      const double t0 = r.edge_thickness(0.75 * A + 0.25 * B, fs),
                   t1 = r.edge_thickness(0.25 * A + 0.75 * B, fs);
      const double half = 0.5 * len;
      const double after = std::max(t0 > 0 ? half / t0 : HUGE_VAL, t1 > 0 ? half / t1 : HUGE_VAL);
      if (!(after < options.min_gain * before)) continue;  // a wedge: no gain
      // Longest-edge closure: where a face of e has a longer edge, the end of that longest-edge
      // path is bisected first (e waits for a later round), so no face is cut across its
      // longest edge; a path ending at a kept edge lets e's split through only if the child
      // along the kept edge keeps its shape.
      const Refiner::Closure c =
          options.longest_edge_closure ? r.closure(e, kept) : r.closure_off(e, kept);
      if (c.kept_end) {
        if (options.max_child_mips > 0 &&
            !r.children_shaped(c.edge[0], c.edge[1], r.faces_of(c.edge[0], c.edge[1]),
                               options.max_child_mips, kept)) {
          ++stats.shape_refusals;
          continue;
        }
      }
      if (edge_key(c.edge[0], c.edge[1]) != edge_key(e[0], e[1])) {
        const auto cs = r.faces_of(c.edge[0], c.edge[1]);
        if (touched_now[std::size_t(cs[0])] || touched_now[std::size_t(cs[1])]) continue;
        std::vector<int> touched;
        r.split(c.edge[0], c.edge[1], cs, touched);
        for (int t : touched) touched_now[std::size_t(t)] = 1;
        ++stats.closure_splits;
        ++splits;
        continue;
      }
      const int m = int(r.V.size());
      std::vector<int> touched;
      r.split(e[0], e[1], fs, touched);
      r.mid_thickness[edge_key(e[0], m)] = t0;
      r.mid_thickness[edge_key(m, e[1])] = t1;
      for (int t : touched) touched_now[std::size_t(t)] = 1;
      ++splits;
    }
    stats.splits += splits;
    ++stats.rounds;
    if (splits == 0 || stats.budget_reached) break;
  }
  r.count(limit, stats.thin_edges_after, stats.max_ratio_after);

  if (stats.splits > 0) stats.refined_faces = r.write(out);
  stats.seconds = watch.seconds();
  if (stats.thin_edges_before > 0)
    log::info("thin refinement: ", stats.thin_edges_before, " input edges longer than ",
              options.max_edge_per_thickness, " x the local thickness (worst ",
              stats.max_ratio_before, "); ", stats.splits, " bisections in ", stats.rounds,
              " rounds refined ", stats.refined_faces, " input faces (", stats.shape_refusals,
              " left out for a child's shape); ", stats.thin_edges_after, " left (worst ",
              stats.max_ratio_after, ")", stats.budget_reached ? ", face budget reached" : "", ", ",
              stats.seconds, " s");
  return out;
}

BeveledSurface refine_poor_shapes(const SurfaceMesh& input, const ShapeRefineOptions& options,
                                  ShapeRefineStats& stats,
                                  std::vector<std::array<int, 2>>& refined_features) {
  Stopwatch watch;
  stats = {};
  refined_features = options.feature_edges;
  const int nf = input.num_faces();
  BeveledSurface out = unbeveled_surface(input, ExtrusionDirections{});
  if (!(options.min_edge > 0) || nf == 0) return out;
  std::set<std::uint64_t> features;
  for (const auto& e : options.feature_edges) features.insert(edge_key(e[0], e[1]));
  auto mips_of = [](const std::vector<Eigen::Vector3d>& V, const std::array<int, 3>& t) {
    return triangle_mips(V[std::size_t(t[0])], V[std::size_t(t[1])], V[std::size_t(t[2])]);
  };
  // Total face angle at each input vertex (bisection points are flat: 2π).
  std::vector<double> angle_sum(std::size_t(input.num_vertices()), 0.0);
  auto corner_angle = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                         const Eigen::Vector3d& r) {
    return std::atan2((q - p).cross(r - p).norm(), (q - p).dot(r - p));
  };
  for (int f = 0; f < nf && options.min_cone_angle > 0; ++f)
    for (int c = 0; c < 3; ++c) {
      const int p = input.F(f, c), q = input.F(f, (c + 1) % 3), r = input.F(f, (c + 2) % 3);
      angle_sum[std::size_t(p)] += corner_angle(
          input.V.row(p).transpose(), input.V.row(q).transpose(), input.V.row(r).transpose());
    }
  // A side of a spike: the face's sharpest corner is a cone tip.
  auto at_spike = [&](const std::vector<Eigen::Vector3d>& V, const std::array<int, 3>& t) {
    if (!(options.min_cone_angle > 0)) return false;
    int sharpest = 0;
    double smallest = HUGE_VAL;
    for (int c = 0; c < 3; ++c) {
      const double a = corner_angle(V[std::size_t(t[std::size_t(c)])],
                                    V[std::size_t(t[std::size_t((c + 1) % 3)])],
                                    V[std::size_t(t[std::size_t((c + 2) % 3)])]);
      if (a < smallest) smallest = a, sharpest = t[std::size_t(c)];
    }
    return sharpest < input.num_vertices() &&
           angle_sum[std::size_t(sharpest)] < options.min_cone_angle;
  };
  // The longest edge of a face that qualifies (poor and long), or {-1, -1}.
  auto target = [&](const std::vector<Eigen::Vector3d>& V, const std::array<int, 3>& t,
                    bool apply_rules) -> std::pair<std::array<int, 2>, double> {
    std::array<int, 2> e{-1, -1};
    double len2 = -1;
    for (int c = 0; c < 3; ++c) {
      const int a = t[std::size_t(c)], b = t[std::size_t((c + 1) % 3)];
      const double l2 = (V[std::size_t(a)] - V[std::size_t(b)]).squaredNorm();
      if (l2 > len2) len2 = l2, e = {a, b};
    }
    const double len = std::sqrt(len2);
    if (!(len > options.min_edge) || !(mips_of(V, t) > options.max_mips)) return {{-1, -1}, 0};
    if (apply_rules && !options.bisect_features && features.count(edge_key(e[0], e[1])))
      return {{-1, -1}, 0};
    if (apply_rules && at_spike(V, t)) return {{-1, -1}, 0};
    return {e, len};
  };
  {
    std::vector<Eigen::Vector3d> V0(std::size_t(input.num_vertices()));
    for (int v = 0; v < input.num_vertices(); ++v) V0[std::size_t(v)] = input.V.row(v).transpose();
    for (int f = 0; f < nf; ++f) {
      const std::array<int, 3> t{input.F(f, 0), input.F(f, 1), input.F(f, 2)};
      if (target(V0, t, false).first[0] < 0) continue;
      ++stats.poor_faces_before;
      stats.spike_faces += at_spike(V0, t);
    }
  }
  if (stats.poor_faces_before == 0) {
    stats.seconds = watch.seconds();
    return out;
  }
  Refiner r(input);
  r.init();
  // Longest first; an entry is stale when its face changed since (generation).
  std::vector<int> generation(std::size_t(nf), 0);
  using Entry = std::tuple<double, int, int>;  // (length, face, generation)
  std::priority_queue<Entry> queue;
  auto push = [&](int f) {
    const auto [e, len] = target(r.V, r.F[std::size_t(f)], true);
    if (e[0] >= 0) queue.emplace(len, f, generation[std::size_t(f)]);
  };
  for (int f = 0; f < nf; ++f) push(f);
  while (!queue.empty()) {
    const auto [len, f, gen] = queue.top();
    queue.pop();
    if (gen != generation[std::size_t(f)]) continue;
    const auto [e, l] = target(r.V, r.F[std::size_t(f)], true);
    if (e[0] < 0) continue;
    if (int(r.F.size()) + 2 > nf + options.max_added_faces) {
      stats.budget_reached = true;
      break;
    }
    const auto fs = r.faces_of(e[0], e[1]);
    const int m = int(r.V.size());
    std::vector<int> touched;
    r.split(e[0], e[1], fs, touched);
    ++stats.splits;
    if (features.erase(edge_key(e[0], e[1]))) {
      features.insert(edge_key(e[0], m));
      features.insert(edge_key(m, e[1]));
      ++stats.feature_splits;
    }
    generation.resize(r.F.size(), 0);
    for (int t : touched) {
      ++generation[std::size_t(t)];
      push(t);
    }
  }
  for (const auto& t : r.F)
    if (target(r.V, t, false).first[0] >= 0) ++stats.poor_faces_after;
  if (stats.splits > 0) {
    stats.refined_faces = r.write(out);
    refined_features.clear();
    for (const std::uint64_t k : features)
      refined_features.push_back({int(k >> 32), int(k & 0xffffffffu)});
  }
  stats.seconds = watch.seconds();
  log::info("shape refinement: ", stats.poor_faces_before, " input faces with a 2-D MIPS above ",
            options.max_mips, " and an edge longer than ", options.min_edge, "; ", stats.splits,
            " bisections (", stats.feature_splits, " on feature edges) refined ",
            stats.refined_faces, " input faces into ",
            r.F.size() - std::size_t(nf) + std::size_t(stats.refined_faces), "; ",
            stats.poor_faces_after, " left (", stats.spike_faces, " at spike tips)",
            stats.budget_reached ? ", face budget reached" : "", ", ", stats.seconds, " s");
  return out;
}

BeveledSurface compose(const BeveledSurface& inner, BeveledSurface outer) {
  CF_VERIFY(outer.input_vertices == inner.mesh.num_vertices() &&
                outer.input_faces == inner.mesh.num_faces(),
            "compose: the outer refinement is not of the inner surface");
  std::vector<int> children(std::size_t(inner.input_faces), 0);
  for (std::size_t f = 0; f < outer.face_parent.size(); ++f) {
    const int mid = outer.face_parent[f];
    outer.face_parent[f] = inner.face_parent[std::size_t(mid)];
    outer.corner_bary[f] = inner.corner_bary[std::size_t(mid)] * outer.corner_bary[f];
    ++children[std::size_t(outer.face_parent[f])];
  }
  outer.input_vertices = inner.input_vertices;
  outer.input_faces = inner.input_faces;
  outer.beveled_faces =
      int(std::count_if(children.begin(), children.end(), [](int c) { return c > 1; }));
  return outer;
}

}  // namespace curvefem::meshing::shell
