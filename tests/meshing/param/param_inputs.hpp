// Generated inputs for the SCAF tests (no data files): a deep Gaussian bump disk, a flat spiral
// strip of several turns, a torus with the two seams that cut it into a disk, several charts.
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "meshing/core/primitives.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::test {

/// Polar-grid disk of radius 1 (centre vertex, `rings` rings of `sectors` vertices) lifted to
/// z = height · exp(−ρ² / (2 width²)); faces counter-clockwise seen from +z.
inline SurfaceMesh bump_disk(int rings, int sectors, double height, double width,
                             Eigen::Vector3d offset = Eigen::Vector3d::Zero()) {
  SurfaceMesh m;
  m.V.resize(1 + rings * sectors, 3);
  m.V.row(0) = Eigen::Vector3d(0, 0, height).transpose() + offset.transpose();
  for (int r = 1; r <= rings; ++r)
    for (int s = 0; s < sectors; ++s) {
      const double rho = double(r) / rings,
                   a = 2 * std::numbers::pi * (s + 0.5 * (r % 2)) / sectors;
      m.V.row(1 + (r - 1) * sectors + s) =
          Eigen::Vector3d(rho * std::cos(a), rho * std::sin(a),
                          height * std::exp(-rho * rho / (2 * width * width)))
              .transpose() +
          offset.transpose();
    }
  std::vector<Eigen::Vector3i> f;
  auto id = [&](int r, int s) { return r == 0 ? 0 : 1 + (r - 1) * sectors + (s % sectors); };
  for (int s = 0; s < sectors; ++s) f.emplace_back(0, id(1, s), id(1, s + 1));
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < sectors; ++s) {
      // ring r is rotated by half a sector when r is odd relative to ring r + 1
      if (r % 2) {
        f.emplace_back(id(r, s), id(r + 1, s + 1), id(r, s + 1));
        f.emplace_back(id(r, s), id(r + 1, s), id(r + 1, s + 1));
      } else {
        f.emplace_back(id(r, s), id(r + 1, s), id(r, s + 1));
        f.emplace_back(id(r, s + 1), id(r + 1, s), id(r + 1, s + 1));
      }
    }
  m.F.resize(Eigen::Index(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) m.F.row(Eigen::Index(i)) = f[i].transpose();
  return m;
}

/// Flat strip of width `width` along the Archimedean spiral ρ = 1 + pitch·θ/(2π), θ ∈ [0,
/// 2π·turns], `segments` segments along and `across` segments across; in the plane z = 0, so the
/// minimum of the symmetric Dirichlet energy is exactly 4 (the strip itself).
inline SurfaceMesh spiral_strip(double turns, int segments, int across, double width,
                                double pitch) {
  SurfaceMesh m;
  const int cols = across + 1;
  m.V.resize((segments + 1) * cols, 3);
  for (int i = 0; i <= segments; ++i) {
    const double t = 2 * std::numbers::pi * turns * i / segments;
    for (int j = 0; j < cols; ++j) {
      const double rho =
          1 + pitch * t / (2 * std::numbers::pi) + width * (double(j) / across - 0.5);
      m.V.row(i * cols + j) << rho * std::cos(t), rho * std::sin(t), 0;
    }
  }
  m.F.resize(2 * segments * across, 3);
  int k = 0;
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < across; ++j) {
      const int a = i * cols + j, b = a + 1, c = a + cols, d = c + 1;  // b outward, c along
      m.F.row(k++) << a, b, d;
      m.F.row(k++) << a, d, c;
    }
  return m;
}

/// Torus (make_torus) and the seams of the meridian i = 0 and of the longitude j = 0.
inline std::pair<SurfaceMesh, std::vector<std::array<int, 2>>> cut_torus(double R, double r, int nu,
                                                                         int nv) {
  SurfaceMesh m = make_torus(R, r, nu, nv);
  std::vector<std::array<int, 2>> seams;
  for (int j = 0; j < nv; ++j) seams.push_back({j, (j + 1) % nv});
  for (int i = 0; i < nu; ++i) seams.push_back({i * nv, ((i + 1) % nu) * nv});
  return {m, seams};
}

/// Concatenation of meshes (separate components).
inline SurfaceMesh concatenate(const std::vector<SurfaceMesh>& parts) {
  SurfaceMesh m;
  int nv = 0, nf = 0;
  for (const auto& p : parts) {
    nv += p.num_vertices();
    nf += p.num_faces();
  }
  m.V.resize(nv, 3);
  m.F.resize(nf, 3);
  nv = nf = 0;
  for (const auto& p : parts) {
    m.V.middleRows(nv, p.num_vertices()) = p.V;
    m.F.middleRows(nf, p.num_faces()) = p.F.array() + nv;
    nv += p.num_vertices();
    nf += p.num_faces();
  }
  return m;
}

}  // namespace curvefem::test
