#include "meshing/shell/geometric_texture.hpp"

#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <map>
#include <numbers>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/core/prism_split.hpp"
#include "meshing/shell/displacement_map.hpp"

namespace curvefem::meshing::shell {

std::vector<std::string> builtin_tile_names() { return {"knob", "ring", "spike"}; }

SurfaceMesh builtin_tile(const std::string& name) {
  const Eigen::Vector3d centroid(1.0 / 3, 1.0 / 3, 0.75);
  if (name == "knob") {
    SurfaceMesh m = make_icosphere(2);
    for (int v = 0; v < m.num_vertices(); ++v)
      m.V.row(v) =
          (centroid + Eigen::Vector3d(0.15 * m.V(v, 0), 0.15 * m.V(v, 1), 0.15 * m.V(v, 2)))
              .transpose();
    return m;
  }
  if (name == "ring") {
    SurfaceMesh m = make_torus(0.15, 0.04, 32, 8);
    for (int v = 0; v < m.num_vertices(); ++v)
      m.V.row(v) = (centroid + Eigen::Vector3d(m.V(v, 0), m.V(v, 1), 2 * m.V(v, 2))).transpose();
    return m;
  }
  if (name == "spike") {
    // A cone: base circle of radius 0.15 at t = 0.55 around the centroid, apex at t = 0.95.
    const int n = 24;
    SurfaceMesh m;
    m.V.resize(n + 2, 3);
    for (int i = 0; i < n; ++i) {
      const double a = 2 * std::numbers::pi * i / n;
      m.V.row(i) << centroid.x() + 0.15 * std::cos(a), centroid.y() + 0.15 * std::sin(a), 0.55;
    }
    m.V.row(n) << centroid.x(), centroid.y(), 0.95;      // apex
    m.V.row(n + 1) << centroid.x(), centroid.y(), 0.55;  // base centre
    m.F.resize(2 * n, 3);
    for (int i = 0; i < n; ++i) {
      m.F.row(i) << i, (i + 1) % n, n;
      m.F.row(n + i) << (i + 1) % n, i, n + 1;
    }
    return m;
  }
  std::string names;
  for (const auto& s : builtin_tile_names()) names += (names.empty() ? "" : ", ") + s;
  throw InputError("unknown texture tile \"" + name + "\" (built-in: " + names +
                   "; or a .obj file in the unit prism)");
}

void check_tile(const SurfaceMesh& tile, const std::string& where) {
  if (tile.num_faces() == 0) throw InputError(where + ": the tile has no faces");
  const double tol = 1e-12;
  for (int v = 0; v < tile.num_vertices(); ++v) {
    const double a = tile.V(v, 0), b = tile.V(v, 1), t = tile.V(v, 2);
    if (!(a >= -tol && b >= -tol && a + b <= 1 + tol && t >= -tol && t <= 1 + tol))
      throw InputError(where + ": tile vertex " + std::to_string(v) + " (" + std::to_string(a) +
                       ", " + std::to_string(b) + ", " + std::to_string(t) +
                       ") is outside the unit prism (a, b >= 0, a + b <= 1, 0 <= t <= 1)");
  }
}

namespace {

/// Splits the triangles of m crossed by the plane g(x) = c·x + d = 0 (strictly: a vertex on the
/// plane is not split), sharing the new vertex of an edge between its two faces; orientation kept.
SurfaceMesh split_by_plane(const SurfaceMesh& m, const Eigen::Vector3d& c, double d) {
  std::vector<Eigen::Vector3d> V;
  for (int v = 0; v < m.num_vertices(); ++v) V.push_back(m.V.row(v).transpose());
  std::vector<double> g(V.size());
  for (std::size_t v = 0; v < V.size(); ++v) g[v] = c.dot(V[v]) + d;
  std::map<std::pair<int, int>, int> cut;
  auto on_edge = [&](int a, int b) {
    const auto key = std::minmax(a, b);
    if (auto it = cut.find(key); it != cut.end()) return it->second;
    const int lo = key.first, hi = key.second;
    const double s = g[std::size_t(lo)] / (g[std::size_t(lo)] - g[std::size_t(hi)]);
    V.push_back(V[std::size_t(lo)] + s * (V[std::size_t(hi)] - V[std::size_t(lo)]));
    g.push_back(0.0);
    cut.emplace(key, int(V.size()) - 1);
    return int(V.size()) - 1;
  };
  std::vector<Eigen::Vector3i> F;
  for (int f = 0; f < m.num_faces(); ++f) {
    const int i[3] = {m.F(f, 0), m.F(f, 1), m.F(f, 2)};
    const double s[3] = {g[std::size_t(i[0])], g[std::size_t(i[1])], g[std::size_t(i[2])]};
    const bool pos = s[0] > 0 || s[1] > 0 || s[2] > 0, neg = s[0] < 0 || s[1] < 0 || s[2] < 0;
    if (!(pos && neg)) {
      F.emplace_back(i[0], i[1], i[2]);
      continue;
    }
    int zero = -1;
    for (int k = 0; k < 3; ++k)
      if (s[k] == 0) zero = k;
    if (zero >= 0) {  // the plane through that corner splits the opposite edge
      const int A = i[zero], B = i[(zero + 1) % 3], C = i[(zero + 2) % 3];
      const int X = on_edge(B, C);
      F.emplace_back(A, B, X);
      F.emplace_back(A, X, C);
      continue;
    }
    int lone = 0;  // the corner alone on its side
    for (int k = 0; k < 3; ++k)
      if ((s[k] > 0) != (s[(k + 1) % 3] > 0) && (s[k] > 0) != (s[(k + 2) % 3] > 0)) lone = k;
    const int A = i[lone], B = i[(lone + 1) % 3], C = i[(lone + 2) % 3];
    const int X = on_edge(A, B), Y = on_edge(C, A);
    F.emplace_back(A, X, Y);
    F.emplace_back(X, B, C);
    F.emplace_back(X, C, Y);
  }
  SurfaceMesh out;
  out.V.resize(Eigen::Index(V.size()), 3);
  for (std::size_t v = 0; v < V.size(); ++v) out.V.row(Eigen::Index(v)) = V[v].transpose();
  out.F.resize(Eigen::Index(F.size()), 3);
  for (std::size_t f = 0; f < F.size(); ++f) out.F.row(Eigen::Index(f)) = F[f].transpose();
  return out;
}

}  // namespace

SurfaceMesh split_tile_at_tets(const SurfaceMesh& tile, bool type_a) {
  // Planes of the rising facets in (a, b, t), h = 2t − 1 (prism_split.hpp; heights as in
  // ShellProjection::point): the middle h = 0; type A: h = a − 1, h = a + b − 1 (lower half),
  // h = a, h = a + b (upper); type B: b in place of a in the first and third.
  SurfaceMesh m = split_by_plane(tile, {0, 0, 2}, -1);  // h = 0
  const Eigen::Vector3d single = type_a ? Eigen::Vector3d(-1, 0, 2) : Eigen::Vector3d(0, -1, 2);
  m = split_by_plane(m, single, 0);        // h = a − 1 (or b − 1)
  m = split_by_plane(m, single, -1);       // h = a (or b)
  m = split_by_plane(m, {-1, -1, 2}, 0);   // h = a + b − 1
  m = split_by_plane(m, {-1, -1, 2}, -1);  // h = a + b
  return m;
}

TexturedSurface apply_geometric_texture(const ShellProjection& onto_input,
                                        const SurfaceMesh& tile) {
  check_tile(tile, "texture tile");
  const Shell& shell = onto_input.shell();
  const SurfaceMesh split[2] = {split_tile_at_tets(tile, false), split_tile_at_tets(tile, true)};
  const int nf = int(shell.F.rows());
  // Copy f starts at vertex first_v[f] and face first_f[f].
  std::vector<Eigen::Index> first_v(std::size_t(nf) + 1, 0), first_f(std::size_t(nf) + 1, 0);
  std::vector<char> pinched(std::size_t(nf), 0);
  TexturedSurface out;
  for (int f = 0; f < nf; ++f) {
    for (int c = 0; c < 3; ++c)
      if (!shell.singular.empty() && shell.singular[std::size_t(shell.F(f, c))])
        pinched[std::size_t(f)] = 1;
    out.skipped_pinched += pinched[std::size_t(f)];
    const SurfaceMesh& t = split[is_type_a(Eigen::Vector3i(shell.F.row(f))) ? 1 : 0];
    const bool copy = !pinched[std::size_t(f)];
    first_v[std::size_t(f) + 1] = first_v[std::size_t(f)] + (copy ? t.num_vertices() : 0);
    first_f[std::size_t(f) + 1] = first_f[std::size_t(f)] + (copy ? t.num_faces() : 0);
  }
  out.mesh.V.resize(first_v.back(), 3);
  out.mesh.F.resize(first_f.back(), 3);
  out.mesh.tags.resize(first_f.back());
  tbb::parallel_for(0, nf, [&](int f) {
    if (pinched[std::size_t(f)]) return;
    const SurfaceMesh& piece = split[is_type_a(Eigen::Vector3i(shell.F.row(f))) ? 1 : 0];
    const int nv = piece.num_vertices(), nt = piece.num_faces();
    for (int v = 0; v < nv; ++v) {
      const double a = piece.V(v, 0), b = piece.V(v, 1), t = piece.V(v, 2);
      const Eigen::Index row = first_v[std::size_t(f)] + v;
      PrismPoint q;
      q.face = f;
      q.u = a;
      q.v = b;
      q.h = 2 * t - 1;
      out.mesh.V.row(row) = onto_input.point(q).transpose();
    }
    for (int k = 0; k < nt; ++k) {
      out.mesh.F.row(first_f[std::size_t(f)] + k) =
          piece.F.row(k).array() + int(first_v[std::size_t(f)]);
      out.mesh.tags[first_f[std::size_t(f)] + k] = f;
    }
  });
  return out;
}

TileSeparation separate_for_tile(Shell& shell, const SurfaceMesh& surface,
                                 const SurfaceMesh& tile) {
  TileSeparation out;
  for (int v = 0; v < tile.num_vertices(); ++v) {
    out.top = out.top || tile.V(v, 2) > 0.5;
    out.base = out.base || tile.V(v, 2) < 0.5;
  }
  const NestedCageOptions defaults;
  if (out.top)
    out.top_failure = separate_shell_side(shell, surface, true, defaults.shrink,
                                          defaults.max_shrink_rounds, out.top_stats);
  if (out.base)
    out.base_failure = separate_shell_side(shell, surface, false, defaults.shrink,
                                           defaults.max_shrink_rounds, out.base_stats);
  return out;
}

}  // namespace curvefem::meshing::shell
