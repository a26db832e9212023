// Construction of the prismatic shell without simplification (reference-notes §3.1–3.4):
//   1. QP extrusion directions; singular vertices get zero-length pillars.
//   2. Pinching: every edge joining two singular vertices is split at its midpoint (direction:
//      the normalized sum of its two face normals), so a face has at most one singular corner.
//   3. Initial half-thickness per vertex: 0.8 × the distance along ±direction to the input
//      (ray cast, ignoring the vertex's own faces), capped (globally, and optionally relative to
//      the vertex's mean edge length); the smaller side is used for both.
//   4. Grading: a corner's step may not exceed twice the sum of the other two (3 rounds).
//   5. Repair worklist until every face is valid: a face failing the exact 24-tet positivity
//      test pulls its corners halfway toward its smallest step; a face whose base or top
//      triangle intersects the input (exact predicates; contact at a singular corner is
//      allowed) halves its corners' steps. Steps only decrease, so this terminates (or fails
//      below 2^-46 of the bounding box, a MeshingError naming the face).

#include "meshing/shell/shell.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <map>
#include <optional>

#include "meshing/core/error.hpp"
#include "meshing/shell/extrusion_direction.hpp"
#include "meshing/shell/local_sheets.hpp"
#include "meshing/shell/prism_positivity.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {

namespace {

using Clock = std::chrono::steady_clock;

void require_closed_oriented_manifold(const SurfaceMesh& s) {
  std::map<std::pair<int, int>, std::pair<int, int>> edges;  // (lo, hi) -> (count, sum of +1/-1)
  for (int f = 0; f < s.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = s.F(f, k), b = s.F(f, (k + 1) % 3);
      auto& e = edges[{std::min(a, b), std::max(a, b)}];
      e.first += 1;
      e.second += a < b ? 1 : -1;
    }
  for (const auto& [e, cs] : edges) {
    if (cs.first != 2)
      throw InputError("edge (" + std::to_string(e.first) + ", " + std::to_string(e.second) +
                           ") has " + std::to_string(cs.first) +
                           " faces: the shell needs a closed manifold surface",
                       ErrorContext{.vertex = e.first});
    if (cs.second != 0)
      throw InputError("faces are inconsistently oriented across edge (" + std::to_string(e.first) +
                           ", " + std::to_string(e.second) + ")",
                       ErrorContext{.vertex = e.first});
  }
}

Shell build_shell_impl(const SurfaceMesh& input, const ExtrusionDirections* given,
                       const ShellOptions& options, ShellStats& stats, const ProgressFn& progress) {
  auto t0 = Clock::now();
  auto stage = [&](const char* name) {
    const auto now = Clock::now();
    stats.stage_seconds.emplace_back(name, std::chrono::duration<double>(now - t0).count());
    t0 = now;
    if (progress) progress(name, 1.0);
  };
  if (input.num_faces() == 0) throw InputError("the input surface has no faces");
  require_closed_oriented_manifold(input);
  stats.input_faces = input.num_faces();
  stats.input_vertices = input.num_vertices();
  const double unit = bbox_longest_edge(input.V);

  // 1. Directions.
  if (given &&
      (given->N.rows() != input.V.rows() || given->singular.size() != std::size_t(input.V.rows())))
    throw InputError("shell: " + std::to_string(given->N.rows()) + " directions for " +
                     std::to_string(input.V.rows()) + " vertices");
  const ExtrusionDirections dirs =
      given ? *given : extrusion_directions(input.V, input.F, options.singularity_tolerance);
  stage("directions");

  // 2. Pinching.
  Shell shell;
  std::vector<Eigen::Vector3d> V(input.V.rows()), N(input.V.rows());
  for (int v = 0; v < input.V.rows(); ++v) {
    V[v] = input.V.row(v);
    N[v] = dirs.N.row(v);
  }
  std::vector<char> singular = dirs.singular;
  std::vector<Eigen::Vector3i> F(input.F.rows());
  std::vector<int> parent(input.F.rows());
  for (int f = 0; f < input.F.rows(); ++f) {
    F[f] = input.F.row(f);
    parent[f] = f;
  }
  {
    // Every edge between two singular vertices is split at its midpoint, whose pillar is the
    // normalized sum of the normals of the faces at the edge (thesis §4.2.5), until no such edge
    // is left: then no prism has more than one singular corner. A face with three singular
    // corners needs three splits and becomes four faces; an edge whose faces changed during a pass
    // (it belongs to a face split across another edge) waits for the next pass, so both sides of
    // every split edge are split together.
    auto face_normal = [&](const Eigen::Vector3i& f) {
      return Eigen::Vector3d((V[f[1]] - V[f[0]]).cross(V[f[2]] - V[f[0]]).normalized());
    };
    auto has_edge = [&](const Eigen::Vector3i& g, int a, int b) {
      for (int k = 0; k < 3; ++k)
        if ((g[k] == a && g[(k + 1) % 3] == b) || (g[k] == b && g[(k + 1) % 3] == a)) return true;
      return false;
    };
    for (;;) {
      std::map<std::pair<int, int>, std::vector<int>> to_split;  // singular-singular edge -> faces
      for (int f = 0; f < int(F.size()); ++f)
        for (int k = 0; k < 3; ++k) {
          const int a = F[f][k], b = F[f][(k + 1) % 3];
          if (singular[a] && singular[b]) to_split[{std::min(a, b), std::max(a, b)}].push_back(f);
        }
      if (to_split.empty()) break;  // every pass splits its first edge at least: it ends
      for (const auto& [e, faces] : to_split) {
        bool current = true;
        for (int f : faces) current &= has_edge(F[f], e.first, e.second);
        if (!current) continue;  // the next pass
        Eigen::Vector3d n = Eigen::Vector3d::Zero();
        for (int f : faces) n += face_normal(F[f]);
        if (!(n.norm() > 1e-9))
          throw MeshingError("edge (" + std::to_string(e.first) + ", " + std::to_string(e.second) +
                                 ") joins two singular vertices and its faces are folded flat onto "
                                 "each other (opposite normals): no pillar sees both",
                             ErrorContext{.vertex = e.first < stats.input_vertices ? e.first : -1,
                                          .face = parent[faces.front()]});
        const int m = int(V.size());
        V.push_back(0.5 * (V[e.first] + V[e.second]));
        N.push_back(n.normalized());
        singular.push_back(0);
        for (int f : faces) {
          // Face (a, b, c) with edge (a, b) becomes (a, m, c) and (m, b, c).
          Eigen::Vector3i g = F[f];
          int k = 0;
          while (!((g[k] == e.first && g[(k + 1) % 3] == e.second) ||
                   (g[k] == e.second && g[(k + 1) % 3] == e.first)))
            ++k;
          const int a = g[k], b = g[(k + 1) % 3], c = g[(k + 2) % 3];
          F[f] = Eigen::Vector3i(a, m, c);
          F.push_back(Eigen::Vector3i(m, b, c));
          parent.push_back(parent[f]);
        }
        ++stats.pinch_splits;
      }
    }
  }
  const int nv = int(V.size()), nf = int(F.size());
  stats.singular_vertices = int(std::count(singular.begin(), singular.end(), 1));
  std::vector<std::vector<int>> vertex_faces(nv);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) vertex_faces[F[f][k]].push_back(f);
  stage("pinching");

  // 3. Initial steps by ray casting against the input.
  const InputSurfaceIndex index(input.V, input.F);
  const std::optional<LocalSheets> sheets =
      options.local_sheets ? std::optional<LocalSheets>(std::in_place, index) : std::nullopt;
  const double cap = options.max_thickness_rel * unit;
  std::vector<double> step(nv, 0.0);
  std::vector<double> edge_sum(nv, 0.0);
  std::vector<int> edge_count(nv, 0);
  if (options.max_thickness_per_edge > 0)
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {  // each interior edge twice, from both faces: a mean anyway
        const int a = F[f][k], b = F[f][(k + 1) % 3];
        const double l = (V[a] - V[b]).norm();
        edge_sum[a] += l;
        edge_sum[b] += l;
        ++edge_count[a];
        ++edge_count[b];
      }
  for (int v = 0; v < nv; ++v) {
    if (singular[v]) continue;
    // Faces to ignore: the input faces whose closure contains this vertex.
    std::vector<int> own;
    for (int f : vertex_faces[v]) own.push_back(parent[f]);
    // Locally injective: only the sheet through v within the cap counts (a farther hit
    // leaves the step at the cap anyway).
    std::vector<int> sheet;
    if (sheets) {
      const Eigen::Vector3d r = Eigen::Vector3d::Constant(cap);
      sheet = sheets->sheet(own, Eigen::AlignedBox3d(V[v] - r, V[v] + r));
    }
    const std::vector<int>* among = sheets ? &sheet : nullptr;
    const double out = index.ray_distance(V[v], N[v], own, among),
                 in = index.ray_distance(V[v], -N[v], own, among);
    step[v] = std::min({cap, 0.8 * out, 0.8 * in});
    if (edge_count[v] > 0)
      step[v] = std::min(step[v], options.max_thickness_per_edge * edge_sum[v] / edge_count[v]);
  }
  stage("ray steps");

  // 4. Grading.
  for (int round = 0; round < options.smoothing_rounds; ++round)
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        double& s = step[F[f][k]];
        const double others = step[F[f][(k + 1) % 3]] + step[F[f][(k + 2) % 3]];
        if (s > 2 * others) s = others;
      }
  stage("grading");

  // 5. Repair worklist: positivity and no intersection with the input.
  auto corners = [&](int f, int side) {  // side -1 base, 0 mid, +1 top
    std::array<Eigen::Vector3d, 3> c;
    for (int k = 0; k < 3; ++k) c[k] = V[F[f][k]] + double(side) * step[F[f][k]] * N[F[f][k]];
    return c;
  };
  auto singular_corners = [&](int f) {
    return std::array<bool, 3>{bool(singular[F[f][0]]), bool(singular[F[f][1]]),
                               bool(singular[F[f][2]])};
  };
  const double floor = std::ldexp(unit, -46);
  std::deque<int> queue;
  std::vector<char> queued(nf, 1);
  for (int f = 0; f < nf; ++f) queue.push_back(f);
  auto requeue_around = [&](int f) {
    for (int k = 0; k < 3; ++k)
      for (int g : vertex_faces[F[f][k]])
        if (!queued[g]) {
          queued[g] = 1;
          queue.push_back(g);
        }
  };
  std::size_t processed = 0;
  while (!queue.empty()) {
    const int f = queue.front();
    queue.pop_front();
    queued[f] = 0;
    if (progress && (++processed % 4096) == 0)
      progress("shell repair", 1.0 - double(queue.size()) / double(nf));
    const auto sing = singular_corners(f);
    bool changed = false;
    for (int attempt = 0; !shell_face_positive(corners(f, -1), corners(f, 0), corners(f, 1), sing);
         ++attempt) {
      double smin = 1e300;
      for (int k = 0; k < 3; ++k)
        if (!sing[k]) smin = std::min(smin, step[F[f][k]]);
      for (int k = 0; k < 3; ++k) {
        double& s = step[F[f][k]];
        if (sing[k]) continue;
        s = attempt < 30 ? 0.5 * (s + smin) : 0.8 * s;
      }
      if (smin < floor || attempt > 400)
        throw MeshingError("shell face " + std::to_string(f) + " (input face " +
                               std::to_string(parent[f]) +
                               ") cannot be made positive: its directions do not see it",
                           ErrorContext{.face = parent[f]});
      changed = true;
      ++stats.shrink_rounds_volume;
    }
    // Locally injective: separation from the prism's local sheet only.
    std::vector<int> sheet;
    if (sheets) {
      Eigen::AlignedBox3d box;
      for (int side : {-1, 0, 1})
        for (const auto& c : corners(f, side)) box.extend(c);
      sheet = sheets->sheet({parent[f]}, box);
    }
    for (int side : {-1, 1}) {
      while (index.triangle_intersects(corners(f, side), sing, F[f], sheets ? &sheet : nullptr)) {
        for (int k = 0; k < 3; ++k) step[F[f][k]] *= 0.5;
        changed = true;
        ++stats.shrink_rounds_intersection;
        double smax = 0;
        for (int k = 0; k < 3; ++k) smax = std::max(smax, step[F[f][k]]);
        if (smax < floor)
          throw MeshingError("shell face " + std::to_string(f) + " (input face " +
                                 std::to_string(parent[f]) + ") cannot be separated from the input",
                             ErrorContext{.face = parent[f]});
      }
    }
    if (changed) {
      requeue_around(f);
      if (!queued[f]) {
        queued[f] = 1;
        queue.push_back(f);
      }
    }
  }
  stage("repair");

  shell.base.resize(nv, 3);
  shell.mid.resize(nv, 3);
  shell.top.resize(nv, 3);
  for (int v = 0; v < nv; ++v) {
    shell.mid.row(v) = V[v].transpose();
    shell.base.row(v) = (V[v] - step[v] * N[v]).transpose();
    shell.top.row(v) = (V[v] + step[v] * N[v]).transpose();
  }
  shell.F.resize(nf, 3);
  for (int f = 0; f < nf; ++f) shell.F.row(f) = F[f].transpose();
  shell.singular = singular;
  shell.face_parent = parent;
  shell.local_sheets = options.local_sheets;
  shell.input_vertex.resize(nv);
  for (int v = 0; v < nv; ++v) shell.input_vertex[v] = v < input.num_vertices() ? v : -1;

  std::vector<double> thick;
  for (int v = 0; v < nv; ++v)
    if (!singular[v]) thick.push_back(step[v] / unit);
  if (!thick.empty()) {
    std::sort(thick.begin(), thick.end());
    stats.min_thickness_rel = thick.front();
    stats.median_thickness_rel = thick[thick.size() / 2];
    stats.max_thickness_rel = thick.back();
  }
  return shell;
}

}  // namespace

Shell build_shell(const SurfaceMesh& input, const ShellOptions& options, ShellStats& stats,
                  const ProgressFn& progress) {
  return build_shell_impl(input, nullptr, options, stats, progress);
}

Shell build_shell(const SurfaceMesh& input, const ExtrusionDirections& directions,
                  const ShellOptions& options, ShellStats& stats, const ProgressFn& progress) {
  return build_shell_impl(input, &directions, options, stats, progress);
}

}  // namespace curvefem::meshing::shell
