#include "meshing/core/primitives.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <vector>

namespace curvefem {

SurfaceMesh make_icosphere(int level, double radius, const Eigen::Vector3d& center) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]),
                c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f.swap(g);
  }
  SurfaceMesh m;
  m.V.resize(v.size(), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.V.row(i) = (center + radius * v[i]).transpose();
  m.F.resize(f.size(), 3);
  for (std::size_t i = 0; i < f.size(); ++i) m.F.row(i) = f[i].transpose();
  return m;
}

SurfaceMesh make_torus(double R, double r, int nu, int nv) {
  SurfaceMesh m;
  m.V.resize(nu * nv, 3);
  const double two_pi = 2.0 * std::numbers::pi;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = two_pi * i / nu, w = two_pi * j / nv;
      m.V.row(i * nv + j) << (R + r * std::cos(w)) * std::cos(u),
          (R + r * std::cos(w)) * std::sin(u), r * std::sin(w);
    }
  m.F.resize(2 * nu * nv, 3);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                d = i * nv + (j + 1) % nv;
      m.F.row(2 * (i * nv + j)) << a, b, c;
      m.F.row(2 * (i * nv + j) + 1) << a, c, d;
    }
  return m;
}

SurfaceMesh make_figure_eight_tube(int n, int m, double r) {
  SurfaceMesh out;
  out.V.resize(n * m, 3);
  const double two_pi = 2.0 * std::numbers::pi;
  for (int i = 0; i < n; ++i) {
    const double t = two_pi * i / n;
    const Eigen::Vector3d c(std::cos(t), std::sin(2 * t) / 2, 0);
    const Eigen::Vector3d d = Eigen::Vector3d(-std::sin(t), std::cos(2 * t), 0).normalized();
    const Eigen::Vector3d z = Eigen::Vector3d::UnitZ(), side = z.cross(d);
    for (int j = 0; j < m; ++j) {
      const double w = two_pi * j / m;
      out.V.row(i * m + j) = (c + r * (std::cos(w) * side + std::sin(w) * z)).transpose();
    }
  }
  out.F.resize(2 * n * m, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const int a = i * m + j, b = ((i + 1) % n) * m + j, c = ((i + 1) % n) * m + (j + 1) % m,
                d = i * m + (j + 1) % m;
      out.F.row(2 * (i * m + j)) << a, c, b;  // (side, z, d) is right-handed: reversed is outward
      out.F.row(2 * (i * m + j) + 1) << a, d, c;
    }
  return out;
}

SurfaceMesh make_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int n) {
  SurfaceMesh m;
  std::map<std::array<int, 3>, int> ids;  // lattice point → vertex id
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> f;
  std::vector<int> tags;
  auto vertex = [&](std::array<int, 3> g) {
    auto [it, inserted] = ids.try_emplace(g, static_cast<int>(v.size()));
    if (inserted) {
      Eigen::Vector3d p;
      for (int d = 0; d < 3; ++d) p[d] = g[d] == n ? hi[d] : lo[d] + (hi[d] - lo[d]) * g[d] / n;
      v.push_back(p);
    }
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          std::array<int, 3> g00{}, g10{}, g11{}, g01{};
          for (auto* g : {&g00, &g10, &g11, &g01}) (*g)[axis] = side * n;
          g00[u] = i, g00[w] = j;
          g10[u] = i + 1, g10[w] = j;
          g11[u] = i + 1, g11[w] = j + 1;
          g01[u] = i, g01[w] = j + 1;
          const int a = vertex(g00), b = vertex(g10), c = vertex(g11), d = vertex(g01);
          // (u, w, axis) is right-handed: a→b→c is counter-clockwise seen from +axis.
          if (side == 1) {
            f.push_back({a, b, c});
            f.push_back({a, c, d});
          } else {
            f.push_back({a, c, b});
            f.push_back({a, d, c});
          }
          tags.push_back(1 + 2 * axis + side);
          tags.push_back(1 + 2 * axis + side);
        }
    }
  m.V.resize(v.size(), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.V.row(i) = v[i].transpose();
  m.F.resize(f.size(), 3);
  for (std::size_t i = 0; i < f.size(); ++i) m.F.row(i) = f[i].transpose();
  m.tags = Eigen::Map<Eigen::VectorXi>(tags.data(), static_cast<Eigen::Index>(tags.size()));
  return m;
}

LagrangeMesh make_cube_tets(int n) {
  LagrangeMesh m;
  m.order = 1;
  const int s = n + 1;
  m.nodes.resize(s * s * s, 3);
  auto id = [s](int i, int j, int k) { return (k * s + j) * s + i; };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        m.nodes.row(id(i, j, k)) << double(i) / n, double(j) / n, double(k) / n;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  m.cells.resize(6 * n * n * n, 4);
  int c = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : perms) {
          std::array<int, 3> g = {i, j, k};
          std::array<int, 4> v;
          v[0] = id(g[0], g[1], g[2]);
          for (int step = 0; step < 3; ++step) {
            g[p[step]] += 1;
            v[step + 1] = id(g[0], g[1], g[2]);
          }
          const Eigen::Vector3d a = m.nodes.row(v[1]) - m.nodes.row(v[0]);
          const Eigen::Vector3d b = m.nodes.row(v[2]) - m.nodes.row(v[0]);
          const Eigen::Vector3d d = m.nodes.row(v[3]) - m.nodes.row(v[0]);
          if (a.dot(b.cross(d)) < 0) std::swap(v[1], v[2]);
          for (int t = 0; t < 4; ++t) m.cells(c, t) = v[t];
          ++c;
        }
  m.cell_tags = Eigen::VectorXi::Ones(m.num_cells());
  return m;
}

LagrangeMesh elevate_order(const LagrangeMesh& linear, int k,
                           const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& deform) {
  const auto& lattice = lagrange_lattice(CellKind::tetrahedron, k);
  LagrangeMesh m;
  m.order = k;
  m.cell_tags = linear.cell_tags;
  m.cells.resize(linear.num_cells(), static_cast<Eigen::Index>(lattice.size()));
  std::map<std::vector<std::pair<int, int>>, int> ids;
  std::vector<Eigen::Vector3d> nodes;
  for (int c = 0; c < linear.num_cells(); ++c)
    for (std::size_t l = 0; l < lattice.size(); ++l) {
      std::vector<std::pair<int, int>> key;
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int i = 0; i < 4; ++i) {
        if (lattice[l][i] == 0) continue;
        key.emplace_back(linear.cells(c, i), lattice[l][i]);
        x += (double(lattice[l][i]) / k) * linear.nodes.row(linear.cells(c, i)).transpose();
      }
      std::sort(key.begin(), key.end());
      auto [it, inserted] = ids.try_emplace(key, static_cast<int>(nodes.size()));
      if (inserted) nodes.push_back(deform(x));
      m.cells(c, static_cast<Eigen::Index>(l)) = it->second;
    }
  m.nodes.resize(static_cast<Eigen::Index>(nodes.size()), 3);
  for (std::size_t i = 0; i < nodes.size(); ++i)
    m.nodes.row(static_cast<Eigen::Index>(i)) = nodes[i].transpose();
  return m;
}

SurfaceMesh make_cylinder(int around, int rows, int rings, double h) {
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> f;
  auto ring = [&](double r, double z) {
    const int first = int(v.size());
    for (int i = 0; i < around; ++i) {
      const double t = 2 * std::numbers::pi * i / around;
      v.emplace_back(r * std::cos(t), r * std::sin(t), z);
    }
    return first;
  };
  auto band = [&](int lo, int hi, bool flip) {  // quads between two rings
    for (int i = 0; i < around; ++i) {
      const int j = (i + 1) % around;
      const int a = lo + i, b = lo + j, c = hi + j, d = hi + i;
      if (!flip) {
        f.emplace_back(a, b, c);
        f.emplace_back(a, c, d);
      } else {
        f.emplace_back(a, c, b);
        f.emplace_back(a, d, c);
      }
    }
  };
  std::vector<int> side;
  for (int r = 0; r <= rows; ++r) side.push_back(ring(1.0, h * r / rows));
  for (int r = 0; r < rows; ++r) band(side[r], side[r + 1], false);
  for (int cap = 0; cap < 2; ++cap) {
    const double z = cap == 0 ? 0.0 : h;
    int outer = cap == 0 ? side.front() : side.back();
    for (int q = rings - 1; q >= 1; --q) {
      const int inner = ring(double(q) / rings, z);
      band(inner, outer, cap == 1);
      outer = inner;
    }
    const int centre = int(v.size());
    v.emplace_back(0, 0, z);
    for (int i = 0; i < around; ++i) {
      const int a = outer + i, b = outer + (i + 1) % around;
      if (cap == 0)
        f.emplace_back(centre, b, a);
      else
        f.emplace_back(centre, a, b);
    }
  }
  SurfaceMesh m;
  m.V.resize(int(v.size()), 3);
  for (int i = 0; i < int(v.size()); ++i) m.V.row(i) = v[i].transpose();
  m.F.resize(int(f.size()), 3);
  for (int i = 0; i < int(f.size()); ++i) m.F.row(i) = f[i].transpose();
  return m;
}

}  // namespace curvefem
