#include "meshing/core/adversarial.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"

namespace curvefem {

namespace {

SurfaceMesh from_lists(const std::vector<Eigen::Vector3d>& V,
                       const std::vector<Eigen::Vector3i>& F) {
  SurfaceMesh m;
  m.V.resize(Eigen::Index(V.size()), 3);
  for (std::size_t i = 0; i < V.size(); ++i) m.V.row(Eigen::Index(i)) = V[i];
  m.F.resize(Eigen::Index(F.size()), 3);
  for (std::size_t i = 0; i < F.size(); ++i) m.F.row(Eigen::Index(i)) = F[i];
  return m;
}

double mean_edge(const SurfaceMesh& m) {
  double sum = 0;
  for (int f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) sum += (m.V.row(m.F(f, k)) - m.V.row(m.F(f, (k + 1) % 3))).norm();
  return sum / (3.0 * double(m.F.rows()));
}

/// Vertices pairwise more than two edges apart, chosen greedily in a seeded random order.
std::vector<int> spread_vertices(const SurfaceMesh& m, int count, unsigned seed) {
  std::vector<std::set<int>> ring(std::size_t(m.V.rows()));
  for (int f = 0; f < m.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ring[std::size_t(m.F(f, k))].insert(m.F(f, (k + 1) % 3));
  std::vector<int> order(std::size_t(m.V.rows()));
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = int(i);
  std::mt19937 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  std::vector<char> blocked(order.size(), 0);
  std::vector<int> out;
  for (int v : order) {
    if (int(out.size()) >= count) break;
    if (blocked[std::size_t(v)]) continue;
    out.push_back(v);
    blocked[std::size_t(v)] = 1;
    for (int a : ring[std::size_t(v)]) {
      blocked[std::size_t(a)] = 1;
      for (int b : ring[std::size_t(a)]) blocked[std::size_t(b)] = 1;
    }
  }
  return out;
}

}  // namespace

SurfaceMesh make_knife_disc(int n, int rings, double rim_half_angle_deg, double c, int slivers) {
  if (n < 8 || rings < 2) throw InputError("knife disc: n >= 8 and rings >= 2");
  const double s = std::tan(rim_half_angle_deg * std::numbers::pi / 180.0);
  auto f = [&](double r) { return s * (1 - r) + c * (1 - r) * (1 - r); };
  std::vector<Eigen::Vector3d> V;
  // top pole, top rings 1..rings-1, rim, bottom rings rings-1..1, bottom pole
  V.push_back({0, 0, f(0)});
  auto ring = [&](double r, double z) {
    const int first = int(V.size());
    for (int i = 0; i < n; ++i) {
      const double a = 2 * std::numbers::pi * i / n;
      V.push_back({r * std::cos(a), r * std::sin(a), z});
    }
    return first;
  };
  // Ring radii j / (rings - 1) for j < rings - 1, then 1 - delta next to the rim, so that the
  // faces at the rim lean by the rim angle (slope s + c delta), not by the coarse rings' chord.
  const double delta = 0.01;
  auto radius = [&](int j) { return j < rings - 1 ? double(j) / (rings - 1) : 1 - delta; };
  std::vector<int> top(rings + 1), bottom(rings + 1);
  top[0] = 0;
  for (int j = 1; j < rings; ++j) top[j] = ring(radius(j), f(radius(j)));
  top[rings] = bottom[rings] = ring(1.0, 0.0);
  for (int j = rings - 1; j >= 1; --j) bottom[j] = ring(radius(j), -f(radius(j)));
  bottom[0] = int(V.size());
  V.push_back({0, 0, -f(0)});
  std::vector<Eigen::Vector3i> F;
  auto at = [&](int first, int i) { return first + (i % n + n) % n; };
  // Caps: fans around the poles (outward: counter-clockwise seen from outside).
  for (int i = 0; i < n; ++i) {
    F.push_back({top[0], at(top[1], i), at(top[1], i + 1)});
    F.push_back({bottom[0], at(bottom[1], i + 1), at(bottom[1], i)});
  }
  std::set<int> sliver_at;
  for (int k = 0; k < slivers; ++k) sliver_at.insert((k * n) / std::max(slivers, 1));
  for (int j = 1; j < rings; ++j) {
    const int A = top[j], B = top[j + 1], a = bottom[j], b = bottom[j + 1];
    for (int i = 0; i < n; ++i) {
      F.push_back({at(a, i), at(b, i + 1), at(b, i)});
      F.push_back({at(a, i), at(a, i + 1), at(b, i + 1)});
      if (j == rings - 1 && sliver_at.count(i)) {
        // Hexagon A_i, A_i+1, A_i+2 | B_i, B_i+1, B_i+2: the sliver (B_i, B_i+1, B_i+2) below
        // the chord B_i B_i+2, and three faces above it.
        F.push_back({at(B, i), at(B, i + 1), at(B, i + 2)});
        F.push_back({at(A, i), at(B, i), at(B, i + 2)});
        F.push_back({at(A, i), at(B, i + 2), at(A, i + 1)});
        F.push_back({at(A, i + 1), at(B, i + 2), at(A, i + 2)});
        // the bottom strip of quad i + 1 still has to be made: done by the loop at i + 1,
        // whose top faces are skipped below
        continue;
      }
      if (j == rings - 1 && sliver_at.count(i - 1 < 0 ? i - 1 + n : i - 1)) continue;
      F.push_back({at(A, i), at(B, i), at(B, i + 1)});
      F.push_back({at(A, i), at(B, i + 1), at(A, i + 1)});
    }
  }
  return from_lists(V, F);
}

SurfaceMesh make_needle_sphere(int level, int needles, double height, double lean_deg,
                               unsigned seed) {
  const SurfaceMesh base = make_icosphere(level);
  std::vector<Eigen::Vector3d> V;
  for (int v = 0; v < base.V.rows(); ++v) V.push_back(base.V.row(v).transpose());
  const std::vector<int> chosen = spread_vertices(base, needles, seed);
  std::vector<char> is_needle(V.size(), 0);
  for (int v : chosen) is_needle[std::size_t(v)] = 1;
  std::map<int, int> tip;  // needle vertex -> tip id (the vertex itself moves out)
  // Per needle vertex v: a tiny ring q_a on each edge (v, a), radius rho = height tan(lean).
  std::map<std::pair<int, int>, int> q;
  const double rho = height * std::tan(lean_deg * std::numbers::pi / 180.0);
  std::vector<Eigen::Vector3i> F;
  for (int f = 0; f < base.F.rows(); ++f) {
    Eigen::Vector3i t = base.F.row(f);
    int k = 0;
    while (k < 3 && !is_needle[std::size_t(t[k])]) ++k;
    if (k == 3) {
      F.push_back(t);
      continue;
    }
    // Rotate so the needle vertex is first: (v, a, b); spread vertices never share a face.
    const int v = t[k], a = t[(k + 1) % 3], b = t[(k + 2) % 3];
    const Eigen::Vector3d c = base.V.row(v).transpose();
    auto ring_point = [&](int w) {
      auto [it, fresh] = q.try_emplace({v, w}, int(V.size()));
      if (fresh) V.push_back(c + rho * (V[std::size_t(w)] - c).normalized());
      return it->second;
    };
    const int qa = ring_point(a), qb = ring_point(b);
    F.push_back({qa, a, b});
    F.push_back({qa, b, qb});
    F.push_back({v, qa, qb});  // the needle's side, v moved to the tip below
  }
  for (int v : chosen) V[std::size_t(v)] = V[std::size_t(v)] * (1.0 + height);
  return from_lists(V, F);
}

SurfaceMesh make_sliver_sphere(int level, int slivers, double t, unsigned seed) {
  SurfaceMesh m = make_icosphere(level);
  std::vector<Eigen::Vector3d> V;
  for (int v = 0; v < m.V.rows(); ++v) V.push_back(m.V.row(v).transpose());
  std::vector<Eigen::Vector3i> F;
  for (int f = 0; f < m.F.rows(); ++f) F.push_back(m.F.row(f).transpose());
  std::mt19937 rng(seed);
  std::set<int> touched;  // faces already split
  for (int n = 0, tries = 0; n < slivers && tries < 100 * slivers; ++tries) {
    const int f = int(rng() % F.size()), k = int(rng() % 3);
    const int a = F[std::size_t(f)][k], b = F[std::size_t(f)][(k + 1) % 3];
    // the face across (a, b)
    int g = -1;
    for (int h = 0; h < int(F.size()) && g < 0; ++h)
      for (int j = 0; j < 3; ++j)
        if (h != f && F[std::size_t(h)][j] == b && F[std::size_t(h)][(j + 1) % 3] == a) g = h;
    if (g < 0 || touched.count(f) || touched.count(g)) continue;
    const int p = int(V.size());
    V.push_back(V[std::size_t(a)] + t * (V[std::size_t(b)] - V[std::size_t(a)]));
    for (int h : {f, g}) {
      const Eigen::Vector3i tri = F[std::size_t(h)];
      int j = 0;
      while (!((tri[j] == a && tri[(j + 1) % 3] == b) || (tri[j] == b && tri[(j + 1) % 3] == a)))
        ++j;
      const int x = tri[j], y = tri[(j + 1) % 3], z = tri[(j + 2) % 3];
      F[std::size_t(h)] = {x, p, z};
      F.push_back({p, y, z});
      touched.insert(h);
      touched.insert(int(F.size()) - 1);
    }
    ++n;
  }
  return from_lists(V, F);
}

SurfaceMesh make_radial_noise_sphere(int level, double amplitude, double fraction, unsigned seed) {
  SurfaceMesh m = make_icosphere(level);
  const double h = mean_edge(m);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), pick(0, 1);
  for (int v = 0; v < m.V.rows(); ++v) {
    if (pick(rng) >= fraction) continue;
    // A radial graph over the sphere's triangulation stays embedded for any radius > 0.
    const double r = std::max(0.2, 1.0 + amplitude * h * u(rng));
    m.V.row(v) *= r;
  }
  return m;
}

SurfaceMesh make_split_ring(double r_in, double r_out, double height, double gap, int n) {
  // A rectangle (r_in..r_out) x (0..height) swept around z from delta to 2 pi - delta, the
  // inner corners of its two flat ends `gap` apart.
  const double delta = std::asin(0.5 * gap / r_in);
  const double prof[4][2] = {{r_in, 0}, {r_out, 0}, {r_out, height}, {r_in, height}};
  std::vector<Eigen::Vector3d> V;
  for (int i = 0; i <= n; ++i) {
    const double a = delta + (2 * std::numbers::pi - 2 * delta) * i / n;
    for (const auto& p : prof) V.push_back({p[0] * std::cos(a), p[0] * std::sin(a), p[1]});
  }
  std::vector<Eigen::Vector3i> F;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < 4; ++j) {
      const int a = 4 * i + j, b = 4 * i + (j + 1) % 4, c = 4 * (i + 1) + (j + 1) % 4,
                d = 4 * (i + 1) + j;
      F.push_back({a, b, c});
      F.push_back({a, c, d});
    }
  F.push_back({0, 2, 1});
  F.push_back({0, 3, 2});
  const int e = 4 * n;
  F.push_back({e, e + 1, e + 2});
  F.push_back({e, e + 2, e + 3});
  SurfaceMesh m = from_lists(V, F);
  // Outward by the signed volume.
  double vol = 0;
  for (const auto& f : F)
    vol += V[std::size_t(f[0])].dot(V[std::size_t(f[1])].cross(V[std::size_t(f[2])]));
  if (vol < 0) m.F.col(1).swap(m.F.col(2));
  return m;
}

SurfaceMesh make_box_with_spikes(int n, int spikes, double radius, double height) {
  const SurfaceMesh box = make_box({0, 0, 0}, {1, 1, 1}, n);
  std::vector<int> top;
  for (int f = 0; f < box.num_faces(); ++f)
    if (box.V(box.F(f, 0), 2) == 1 && box.V(box.F(f, 1), 2) == 1 && box.V(box.F(f, 2), 2) == 1)
      top.push_back(f);
  if (spikes < 0 || spikes > int(top.size()))
    throw InputError("make_box_with_spikes: " + std::to_string(spikes) + " spikes on " +
                     std::to_string(top.size()) + " top faces");
  std::vector<Eigen::Vector3d> V(box.V.rows());
  for (int v = 0; v < int(V.size()); ++v) V[std::size_t(v)] = box.V.row(v).transpose();
  std::vector<Eigen::Vector3i> F;
  std::set<int> spiked;
  for (int i = 0; i < spikes; ++i)  // spread over the top, away from its rim when there is room
    spiked.insert(top[std::size_t((2 * i + 1) * int(top.size()) / (2 * spikes))]);
  for (int f = 0; f < box.num_faces(); ++f) {
    const Eigen::Vector3i c = box.F.row(f).transpose();
    if (!spiked.count(f)) {
      F.push_back(c);
      continue;
    }
    const Eigen::Vector3d g =
        (V[std::size_t(c[0])] + V[std::size_t(c[1])] + V[std::size_t(c[2])]) / 3;
    const int ring = int(V.size());
    for (int k = 0; k < 3; ++k) V.push_back(g + radius * (V[std::size_t(c[k])] - g).normalized());
    const int tip = int(V.size());
    V.push_back(g + Eigen::Vector3d(0, 0, height));
    for (int k = 0; k < 3; ++k) {
      const int a = c[k], b = c[(k + 1) % 3], p = ring + k, q = ring + (k + 1) % 3;
      F.emplace_back(a, b, q);
      F.emplace_back(a, q, p);
      F.emplace_back(p, q, tip);
    }
  }
  return from_lists(V, F);
}

SurfaceMesh make_strip_cylinder(int n_bottom, int n_top, double radius, double height, int rings) {
  if (n_bottom < 3 || n_top < 3 || rings < 1 || !(radius > 0) || !(height > 0))
    throw InputError("strip cylinder: n >= 3 on both rims, rings >= 1, radius and height > 0");
  const double turn = 0.37;  // the top rim's offset, in its own spacing
  std::vector<Eigen::Vector3d> V;
  auto angle = [](int i, int n, double offset) { return 2 * std::numbers::pi * (i + offset) / n; };
  auto ring = [&](int n, double r, double z, double offset) {
    const int first = int(V.size());
    for (int i = 0; i < n; ++i)
      V.push_back({r * std::cos(angle(i, n, offset)), r * std::sin(angle(i, n, offset)), z});
    return first;
  };
  const int bottom = ring(n_bottom, radius, 0.0, 0.0), top = ring(n_top, radius, height, turn);
  std::vector<Eigen::Vector3i> F;
  // The side: advance on whichever rim has the next vertex at the smaller angle.
  for (int i = 0, j = 0; i < n_bottom || j < n_top;) {
    const bool bottom_next =
        j >= n_top || (i < n_bottom && angle(i + 1, n_bottom, 0.0) < angle(j + 1, n_top, turn));
    if (bottom_next) {
      F.push_back({bottom + i % n_bottom, bottom + (i + 1) % n_bottom, top + j % n_top});
      ++i;
    } else {
      F.push_back({bottom + i % n_bottom, top + (j + 1) % n_top, top + j % n_top});
      ++j;
    }
  }
  // The caps: bands between concentric rings, then a fan (outward: −z at the bottom).
  for (int cap = 0; cap < 2; ++cap) {
    const int n = cap == 0 ? n_bottom : n_top;
    const double offset = cap == 0 ? 0.0 : turn, z = cap == 0 ? 0.0 : height;
    int outer = cap == 0 ? bottom : top;
    for (int q = rings - 1; q >= 1; --q) {
      const int inner = ring(n, radius * q / rings, z, offset);
      for (int k = 0; k < n; ++k) {
        const int l = (k + 1) % n, a = inner + k, b = inner + l, c = outer + l, d = outer + k;
        if (cap == 0) {
          F.push_back({a, b, c});
          F.push_back({a, c, d});
        } else {
          F.push_back({a, c, b});
          F.push_back({a, d, c});
        }
      }
      outer = inner;
    }
    const int centre = int(V.size());
    V.push_back({0, 0, z});
    for (int k = 0; k < n; ++k) {
      const int a = outer + k, b = outer + (k + 1) % n;
      F.push_back(cap == 0 ? Eigen::Vector3i{centre, b, a} : Eigen::Vector3i{centre, a, b});
    }
  }
  return from_lists(V, F);
}

const std::vector<AdversarialSurface>& adversarial_surfaces() {
  static const std::vector<AdversarialSurface> list = {
      {"knife_disc",
       "a disc whose rim is a 0.4° knife edge (0.25° + the last ring): every rim "
       "vertex singular"},
      {"knife_disc_slivers",
       "the knife disc with 6 rim slivers: faces with three singular corners, min angle 0.1°"},
      {"knife_disc_sharp", "a 0.15° knife edge, 12 slivers"},
      {"knife_disc_fine", "a 0.4° knife edge with 256 rim vertices and 24 slivers"},
      {"needle_sphere_1", "an icosphere with 1 needle of lean 0.4° (singular tip)"},
      {"needle_sphere_8", "8 needles"},
      {"needle_sphere_32", "32 needles on a level-4 sphere"},
      {"needle_sphere_long", "8 needles as long as the radius, lean 0.2°"},
      {"sliver_sphere_001", "40 slivers of about 0.01° (edges split at 1e-4)"},
      {"sliver_sphere_0001", "40 slivers of about 0.001° (edges split at 1e-5)"},
      {"sliver_sphere_many", "400 slivers of about 0.01° on a level-4 sphere"},
      {"noise_sphere_05", "radial noise of 0.5 edge on every vertex"},
      {"noise_sphere_2", "radial noise of 2 edges on every vertex: faces tilted up to 60°"},
      {"noise_sphere_20", "radial noise of 20 edges on every vertex: folds, singular clusters"},
      {"noise_sphere_5", "radial noise of 5 edges on 10% of the vertices: spikes and pits"},
      {"noise_sphere_2_l4", "radial noise of 2 edges on a level-4 sphere"},
      {"noise_sphere_big", "radial noise of 1 edge on a level-7 sphere (327,680 faces)"},
      {"thin_plate_05", "a 1 x 1 plate 0.5 ε thick"},
      {"thin_plate_01", "a 1 x 1 plate 0.1 ε thick"},
      {"thin_plate_fine", "a plate 0.5 ε thick, 16 x 16 quads per side"},
      {"thin_tube_05", "a torus whose tube is 0.5 ε across"},
      {"thin_tube_2", "a torus whose tube is 2 ε across"},
      {"split_ring_01", "a ring cut by a slit 0.1 ε wide: two flat faces in near contact"},
      {"split_ring_001", "the ring with a slit of 0.01 ε"},
      {"split_ring_thin", "a thin ring (wall 0.5 ε) with a 0.1 ε slit"},
      {"torus_fat", "a torus with R = 1, r = 0.9: a near-closed hole"},
      {"torus_coarse", "a 12 x 6 torus: large flat facets, 30° creases"},
      {"cylinder_sharp", "a cylinder with sharp rims (90° curved features)"},
      {"cylinder_flat", "a flat cylinder (height 0.05): two rims close together"},
      {"strip_cylinder",
       "a CAD-style cylinder (radius 1, length 4): its side one band of needle triangles between "
       "rims of 256 and 128 vertices"},
      {"box_sharp", "a unit box, 8 x 8 quads per side (sharp CAD edges and corners)"},
      {"box_thin_long", "a 1 x 0.02 x 0.02 bar: a needle-like CAD part"},
      {"box_small_spikes",
       "a unit box (16 x 16 quads per side) with 6 sharp spikes 0.7 ε high and 0.6 ε across on "
       "its top: feature curves smaller than ε, ending in corners"},
      {"sphere_coarse", "an icosahedron: 20 faces, every vertex a cone point"},
      {"kissing_spheres_01", "two unit spheres 0.1 ε apart (two components): curved near contact"},
      {"kissing_spheres_001", "two unit spheres 0.01 ε apart"},
      {"sphere_fine", "a level-6 icosphere (81,920 faces)"},
  };
  return list;
}

SurfaceMesh make_adversarial(const std::string& name) {
  const double eps = 0.01;  // the default ε, relative to the longest bbox edge
  if (name == "knife_disc") return make_knife_disc(64, 8, 0.25, 0.3, 0);
  if (name == "knife_disc_slivers") return make_knife_disc(64, 8, 0.25, 0.3, 6);
  if (name == "knife_disc_sharp") return make_knife_disc(64, 8, 0.1, 0.3, 12);
  if (name == "knife_disc_fine") return make_knife_disc(256, 12, 0.25, 0.3, 24);
  if (name == "needle_sphere_1") return make_needle_sphere(3, 1, 0.3, 0.4, 1);
  if (name == "needle_sphere_8") return make_needle_sphere(3, 8, 0.3, 0.4, 2);
  if (name == "needle_sphere_32") return make_needle_sphere(4, 32, 0.3, 0.4, 3);
  if (name == "needle_sphere_long") return make_needle_sphere(3, 8, 1.0, 0.2, 4);
  if (name == "sliver_sphere_001") return make_sliver_sphere(3, 40, 1e-4, 5);
  if (name == "sliver_sphere_0001") return make_sliver_sphere(3, 40, 1e-5, 6);
  if (name == "sliver_sphere_many") return make_sliver_sphere(4, 400, 1e-4, 7);
  if (name == "noise_sphere_05") return make_radial_noise_sphere(3, 0.5, 1.0, 8);
  if (name == "noise_sphere_2") return make_radial_noise_sphere(3, 2.0, 1.0, 9);
  if (name == "noise_sphere_20") return make_radial_noise_sphere(3, 20.0, 1.0, 13);
  if (name == "noise_sphere_5") return make_radial_noise_sphere(3, 5.0, 0.1, 10);
  if (name == "noise_sphere_2_l4") return make_radial_noise_sphere(4, 2.0, 1.0, 11);
  if (name == "noise_sphere_big") return make_radial_noise_sphere(7, 1.0, 1.0, 12);
  // Plates and tubes: thickness relative to ε of their own bbox (longest edge about 1 or 2).
  if (name == "thin_plate_05") return make_box({0, 0, 0}, {1, 1, 0.5 * eps}, 4);
  if (name == "thin_plate_01") return make_box({0, 0, 0}, {1, 1, 0.1 * eps}, 4);
  if (name == "thin_plate_fine") return make_box({0, 0, 0}, {1, 1, 0.5 * eps}, 16);
  if (name == "thin_tube_05") return make_torus(1.0, 0.5 * (eps * 2.0) / 2, 96, 8);
  if (name == "thin_tube_2") return make_torus(1.0, 2.0 * (eps * 2.0) / 2, 96, 8);
  if (name == "split_ring_01") return make_split_ring(0.6, 1.0, 0.4, 0.1 * eps * 2.0, 64);
  if (name == "split_ring_001") return make_split_ring(0.6, 1.0, 0.4, 0.01 * eps * 2.0, 64);
  if (name == "split_ring_thin") return make_split_ring(0.99, 1.0, 0.4, 0.1 * eps * 2.0, 96);
  if (name == "torus_fat") return make_torus(1.0, 0.9, 64, 48);
  if (name == "torus_coarse") return make_torus(1.0, 0.4, 12, 6);
  if (name == "cylinder_sharp") return make_cylinder(48, 8, 4, 2.0);
  if (name == "cylinder_flat") return make_cylinder(64, 2, 6, 0.05);
  if (name == "strip_cylinder") return make_strip_cylinder(256, 128, 1.0, 4.0, 6);
  if (name == "box_sharp") return make_box({0, 0, 0}, {1, 1, 1}, 8);
  if (name == "box_small_spikes") return make_box_with_spikes(16, 6, 0.3 * eps, 0.7 * eps);
  if (name == "box_thin_long") return make_box({0, 0, 0}, {1, 0.02, 0.02}, 4);
  if (name == "sphere_coarse") return make_icosphere(0);
  if (name == "kissing_spheres_01" || name == "kissing_spheres_001") {
    // bbox 4 x 2 x 2: ε = 0.04 absolute
    const double gap = (name == "kissing_spheres_01" ? 0.1 : 0.01) * eps * 4.0;
    const SurfaceMesh a = make_icosphere(4), b = make_icosphere(4, 1.0, {2.0 + gap, 0, 0});
    SurfaceMesh m;
    m.V.resize(a.V.rows() + b.V.rows(), 3);
    m.V << a.V, b.V;
    m.F.resize(a.F.rows() + b.F.rows(), 3);
    m.F << a.F, b.F.array() + int(a.V.rows());
    return m;
  }
  if (name == "sphere_fine") return make_icosphere(6);
  std::string known;
  for (const auto& s : adversarial_surfaces()) known += (known.empty() ? "" : ", ") + s.name;
  throw InputError("unknown adversarial surface '" + name + "' (known: " + known + ")");
}

}  // namespace curvefem
