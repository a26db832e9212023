#include "meshing/shell/displacement_map.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/prism_split.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

/// The level-L subdivision of the faces F (over nv vertices), as ids of its points: per face and
/// sample (header order) the global point id; per point its owner (smallest face holding it, and
/// the sample there); the L² triangles per face.
struct Subdivision {
  int level = 1, points = 0;
  std::vector<int> id;                     // faces × samples_per_face
  std::vector<std::pair<int, int>> owner;  // per point: (face, sample)
  Eigen::MatrixXi triangles;               // faces·L² × 3
  std::vector<int> parent;                 // per triangle
};

/// (u, v) = (i, j) / L of sample s in header order.
std::vector<std::pair<int, int>> sample_grid(int L) {
  std::vector<std::pair<int, int>> g;
  for (int i = 0; i <= L; ++i)
    for (int j = 0; i + j <= L; ++j) g.emplace_back(i, j);
  return g;
}

Subdivision subdivide(const Eigen::MatrixXi& F, int nv, int L) {
  Subdivision s;
  s.level = L;
  const int nf = int(F.rows()), S = samples_per_face(L);
  std::map<std::pair<int, int>, int> edges;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      edges.emplace(std::minmax(a, b), int(edges.size()));
    }
  const int ne = int(edges.size()), interior = (L - 1) * (L - 2) / 2;
  const int edge_first = nv, face_first = nv + ne * (L - 1);
  s.points = face_first + nf * std::max(interior, 0);
  // Point id of the point at fraction k / L from a to b on edge {a, b}.
  auto edge_point = [&](int a, int b, int k) {
    const int e = edges.at(std::minmax(a, b));
    return edge_first + e * (L - 1) + (a < b ? k : L - k) - 1;
  };
  const auto grid = sample_grid(L);
  s.id.assign(std::size_t(nf) * S, -1);
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3i Ff = F.row(f);
    const int r = min_rotation(Ff);
    const int c0 = Ff[r], c1 = Ff[(r + 1) % 3], c2 = Ff[(r + 2) % 3];
    int local = 0;
    for (int t = 0; t < S; ++t) {
      const auto [i, j] = grid[std::size_t(t)];
      int p;
      if (i == 0 && j == 0)
        p = c0;
      else if (i == L)
        p = c1;
      else if (j == L)
        p = c2;
      else if (j == 0)
        p = edge_point(c0, c1, i);
      else if (i == 0)
        p = edge_point(c0, c2, j);
      else if (i + j == L)
        p = edge_point(c1, c2, j);
      else
        p = face_first + f * interior + local++;
      s.id[std::size_t(f) * S + t] = p;
    }
  }
  s.owner.assign(std::size_t(s.points), {-1, -1});
  for (int f = 0; f < nf; ++f)
    for (int t = 0; t < S; ++t) {
      auto& o = s.owner[std::size_t(s.id[std::size_t(f) * S + t])];
      if (o.first < 0) o = {f, t};
    }
  // Triangles: in (i, j) the corner order (c0, c1, c2) is (0,0), (L,0), (0,L), the face's own.
  std::vector<std::vector<int>> index(std::size_t(L) + 1, std::vector<int>(std::size_t(L) + 1, -1));
  for (int t = 0; t < S; ++t) index[std::size_t(grid[t].first)][std::size_t(grid[t].second)] = t;
  s.triangles.resize(Eigen::Index(nf) * L * L, 3);
  s.parent.reserve(std::size_t(nf) * L * L);
  int row = 0;
  for (int f = 0; f < nf; ++f) {
    auto at = [&](int i, int j) { return s.id[std::size_t(f) * S + index[i][j]]; };
    for (int i = 0; i < L; ++i)
      for (int j = 0; i + j < L; ++j) {
        s.triangles.row(row++) << at(i, j), at(i + 1, j), at(i, j + 1);
        s.parent.push_back(f);
        if (i + j + 1 < L) {
          s.triangles.row(row++) << at(i + 1, j), at(i + 1, j + 1), at(i, j + 1);
          s.parent.push_back(f);
        }
      }
  }
  return s;
}

/// Heights of the 7 fiber points of fiber_points (same walk as ShellProjection::point).
std::array<double, 7> fiber_heights(bool type_a, const std::array<double, 3>& w) {
  std::array<double, 7> out;
  int n = 0;
  for (int half = 0; half < 2; ++half)
    for (int i = half; i < 4; ++i) {
      std::array<int, 3> sorted = rising_facets(type_a)[std::size_t(i)];
      std::sort(sorted.begin(), sorted.end(), [](int a, int b) { return a % 3 < b % 3; });
      double h = half;
      for (int k = 0; k < 3; ++k) h -= sorted[std::size_t(k)] < 3 ? w[std::size_t(k)] : 0.0;
      out[std::size_t(n++)] = h;
    }
  return out;
}

/// h of the fiber point closest to x (x is on the fiber up to rounding).
double height_on_fiber(const std::array<Eigen::Vector3d, 7>& p, const std::array<double, 7>& H,
                       const Eigen::Vector3d& x) {
  double best = std::numeric_limits<double>::infinity(), h = 0;
  for (std::size_t j = 0; j + 1 < 7; ++j) {
    const Eigen::Vector3d d = p[j + 1] - p[j];
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((x - p[j]).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double dist = (p[j] + t * d - x).squaredNorm();
    if (dist < best) {
      best = dist;
      h = H[j] + t * (H[j + 1] - H[j]);
    }
  }
  return h;
}

std::array<double, 3> weights(int L, int i, int j) {
  const double u = double(i) / L, v = double(j) / L;
  return {1 - u - v, u, v};
}

}  // namespace

std::optional<double> input_height(const ShellProjection& onto_input, int face, double u,
                                   double v) {
  PrismPoint q;
  q.face = face;
  q.u = u;
  q.v = v;
  const auto s = onto_input.project(q);
  if (!s) return std::nullopt;
  const bool type_a = is_type_a(Eigen::Vector3i(onto_input.shell().F.row(face)));
  return height_on_fiber(onto_input.fiber(face, u, v), fiber_heights(type_a, {1 - u - v, u, v}),
                         s->position);
}

DisplacementMap bake_displacement_map(const ShellProjection& onto_input, int level) {
  if (level < 1) throw InputError("displacement map: the level must be at least 1");
  const Shell& shell = onto_input.shell();
  DisplacementMap map;
  map.level = level;
  map.faces = int(shell.F.rows());
  const int S = samples_per_face(level);
  map.h.assign(std::size_t(map.faces) * S, k_nan);
  const auto grid = sample_grid(level);
  tbb::parallel_for(0, map.faces, [&](int f) {
    for (int t = 0; t < S; ++t) {
      const auto [i, j] = grid[std::size_t(t)];
      const std::array<double, 3> w = weights(level, i, j);
      if (const auto h = input_height(onto_input, f, w[1], w[2]))
        map.h[std::size_t(f) * S + t] = *h;
    }
  });
  map.failures =
      int(std::count_if(map.h.begin(), map.h.end(), [](double h) { return std::isnan(h); }));
  return map;
}

Reconstruction reconstruct(const Shell& shell, const DisplacementMap& map) {
  if (map.faces != shell.F.rows())
    throw InputError("displacement map: " + std::to_string(map.faces) + " faces, the shell has " +
                     std::to_string(shell.F.rows()));
  const int L = map.level, S = samples_per_face(L);
  const Subdivision sub = subdivide(shell.F, int(shell.mid.rows()), L);
  SurfaceMesh middle;
  middle.V = shell.mid;
  middle.F = shell.F;
  const ShellProjection prisms(shell, middle);  // point() reads the shell's corners only
  const auto grid = sample_grid(L);
  Reconstruction out;
  out.mesh.V.resize(sub.points, 3);
  tbb::parallel_for(0, sub.points, [&](int p) {
    const auto [f, t] = sub.owner[std::size_t(p)];
    const auto [i, j] = grid[std::size_t(t)];
    const std::array<double, 3> w = weights(L, i, j);
    const double h = map.h[std::size_t(f) * S + t];
    PrismPoint q;
    q.face = f;
    q.u = w[1];
    q.v = w[2];
    q.h = std::isnan(h) ? 0.0 : h;
    out.mesh.V.row(p) = prisms.point(q).transpose();
  });
  out.mesh.F = sub.triangles;
  out.face_parent = sub.parent;
  return out;
}

Reconstruction reconstruct_along_normals(const Shell& shell, const SurfaceMesh& input, int level,
                                         double reach, int* missed) {
  if (level < 1) throw InputError("displacement map: the level must be at least 1");
  const int L = level;
  const Subdivision sub = subdivide(shell.F, int(shell.mid.rows()), L);
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(shell.mid.rows(), 3);
  for (Eigen::Index f = 0; f < shell.F.rows(); ++f) {
    const Eigen::Vector3d a = shell.mid.row(shell.F(f, 0)), b = shell.mid.row(shell.F(f, 1)),
                          c = shell.mid.row(shell.F(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);  // area-weighted
    for (int k = 0; k < 3; ++k) N.row(shell.F(f, k)) += n.transpose();
  }
  const InputSurfaceIndex index(input.V, input.F);
  const auto grid = sample_grid(L);
  Reconstruction out;
  out.mesh.V.resize(sub.points, 3);
  std::vector<char> miss(std::size_t(sub.points), 0);
  tbb::parallel_for(0, sub.points, [&](int p) {
    const auto [f, t] = sub.owner[std::size_t(p)];
    const auto [i, j] = grid[std::size_t(t)];
    const std::array<double, 3> w = weights(L, i, j);
    const Eigen::Vector3i Ff = shell.F.row(f);
    const int r = min_rotation(Ff);
    Eigen::Vector3d x = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const int v = Ff[(r + k) % 3];
      x += w[std::size_t(k)] * Eigen::Vector3d(shell.mid.row(v));
      n += w[std::size_t(k)] * Eigen::Vector3d(N.row(v)).normalized();
    }
    n.normalize();
    Eigen::Vector3d best = x;
    double best_d = std::numeric_limits<double>::infinity();
    for (const double sign : {1.0, -1.0}) {
      Eigen::Vector3d bary;
      const int g = index.segment_hit(x, x + sign * reach * n, bary);
      if (g < 0) continue;
      Eigen::Vector3d y = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) y += bary[k] * Eigen::Vector3d(input.V.row(input.F(g, k)));
      if ((y - x).norm() < best_d) {
        best_d = (y - x).norm();
        best = y;
      }
    }
    if (!std::isfinite(best_d)) miss[std::size_t(p)] = 1;
    out.mesh.V.row(p) = best.transpose();
  });
  if (missed) *missed = int(std::count(miss.begin(), miss.end(), 1));
  out.mesh.F = sub.triangles;
  out.face_parent = sub.parent;
  return out;
}

FiberCheck check_on_fibers(const ShellProjection& projection, const DisplacementMap& map,
                           const Reconstruction& rebuilt) {
  const Shell& shell = projection.shell();
  const int L = map.level;
  const Subdivision sub = subdivide(shell.F, int(shell.mid.rows()), L);
  CF_VERIFY(sub.points == rebuilt.mesh.num_vertices(),
            "check_on_fibers: the rebuilt surface is not this map's subdivision");
  const auto grid = sample_grid(L);
  std::vector<double> offset(std::size_t(sub.points), 0.0);
  std::vector<char> lost(std::size_t(sub.points), 0);
  tbb::parallel_for(0, sub.points, [&](int p) {
    const auto [f, t] = sub.owner[std::size_t(p)];
    const auto [i, j] = grid[std::size_t(t)];
    const std::array<double, 3> w = weights(L, i, j);
    PrismPoint sample;
    sample.face = f;
    sample.u = w[1];
    sample.v = w[2];
    const auto q = projection.locate(Eigen::Vector3d(rebuilt.mesh.V.row(p)));
    if (!q) {
      lost[std::size_t(p)] = 1;
      return;
    }
    PrismPoint on_middle = *q;
    on_middle.h = 0;
    offset[std::size_t(p)] = (projection.point(on_middle) - projection.point(sample)).norm();
  });
  FiberCheck c;
  c.not_located = int(std::count(lost.begin(), lost.end(), 1));
  for (double d : offset) c.max_offset = std::max(c.max_offset, d);
  return c;
}

void write_displacement_map(const std::string& path, const DisplacementMap& map) {
  std::ostringstream o;
  o << "curvefem-displacement-map 1\nlevel " << map.level << " faces " << map.faces << "\n";
  o << std::setprecision(17);
  const int S = samples_per_face(map.level);
  for (int f = 0; f < map.faces; ++f) {
    for (int t = 0; t < S; ++t) {
      const double h = map.h[std::size_t(f) * S + t];
      o << (t ? " " : "");
      if (std::isnan(h))
        o << "nan";
      else
        o << h;
    }
    o << "\n";
  }
  write_text_file_atomic(path, o.str());
}

DisplacementMap read_displacement_map(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open displacement map " + path);
  auto fail = [&](int line, const std::string& what) {
    throw InputError(path + ":" + std::to_string(line) + ": " + what);
  };
  std::string line;
  if (!std::getline(in, line) || line != "curvefem-displacement-map 1")
    fail(1, "not a curvefem displacement map (first line \"curvefem-displacement-map 1\")");
  DisplacementMap map;
  std::string w1, w2;
  if (!std::getline(in, line)) fail(2, "missing \"level L faces N\"");
  {
    std::istringstream s(line);
    if (!(s >> w1 >> map.level >> w2 >> map.faces) || w1 != "level" || w2 != "faces" ||
        map.level < 1 || map.faces < 0)
      fail(2, "expected \"level L faces N\" with L >= 1, N >= 0");
  }
  const int S = samples_per_face(map.level);
  map.h.reserve(std::size_t(map.faces) * S);
  for (int f = 0; f < map.faces; ++f) {
    const int number = f + 3;
    if (!std::getline(in, line)) fail(number, "missing the heights of face " + std::to_string(f));
    std::istringstream s(line);
    std::string word;
    int count = 0;
    while (s >> word) {
      double h = k_nan;
      if (word == "nan") {
        ++map.failures;
      } else {
        std::size_t used = 0;
        try {
          h = std::stod(word, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used != word.size() || !(h >= -1.0 && h <= 1.0))
          fail(number, "height \"" + word + "\" is not a number in [-1, 1]");
      }
      map.h.push_back(h);
      ++count;
    }
    if (count != S)
      fail(number, "face " + std::to_string(f) + " has " + std::to_string(count) +
                       " heights, level " + std::to_string(map.level) + " needs " +
                       std::to_string(S));
  }
  return map;
}

}  // namespace curvefem::meshing::shell
