#include "meshing/shell/projection.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "meshing/shell/prism_location.hpp"
#include "meshing/shell/section.hpp"
#include "meshing/shell/shell_geometry.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {

struct ShellProjection::Impl {
  const Shell& shell;
  InputSurfaceIndex input;
  double cell = 1;
  Eigen::Vector3d origin;
  std::unordered_map<std::int64_t, std::vector<int>> grid;
  std::vector<Eigen::AlignedBox3d> boxes;  // per prism

  Impl(const Shell& s, const SurfaceMesh& in) : shell(s), input(in.V, in.F) {}

  // Corner c (0..5) of half `half` (0: base→mid, 1: mid→top) of face f, rotated order.
  Eigen::Vector3d corner(int f, int half, int c) const {
    const Eigen::Vector3i F = shell.F.row(f);
    const int r = min_rotation(F);
    const int v = F[(r + c % 3) % 3];
    const Eigen::MatrixXd& lower = half == 0 ? shell.base : shell.mid;
    const Eigen::MatrixXd& upper = half == 0 ? shell.mid : shell.top;
    return c < 3 ? Eigen::Vector3d(lower.row(v)) : Eigen::Vector3d(upper.row(v));
  }
  std::int64_t key(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d q = (p - origin) / cell;
    const std::int64_t i = std::int64_t(std::floor(q.x())), j = std::int64_t(std::floor(q.y())),
                       k = std::int64_t(std::floor(q.z()));
    return (i & 0x1fffff) | ((j & 0x1fffff) << 21) | ((k & 0x1fffff) << 42);
  }
};

ShellProjection::ShellProjection(const Shell& shell, const SurfaceMesh& input)
    : m_impl(std::make_unique<Impl>(shell, input)) {
  Impl& m = *m_impl;
  const int nf = int(shell.F.rows());
  std::vector<Eigen::AlignedBox3d>& boxes = m.boxes;
  boxes.resize(nf);
  double diag = 0;
  m.origin = shell.base.colwise().minCoeff().cwiseMin(shell.top.colwise().minCoeff()).transpose();
  for (int f = 0; f < nf; ++f) {
    for (int half = 0; half < 2; ++half)
      for (int c = 0; c < 6; ++c) boxes[f].extend(m.corner(f, half, c));
    diag += boxes[f].diagonal().norm();
  }
  m.cell = std::max(diag / std::max(nf, 1), 1e-300);
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3d lo = (boxes[f].min() - m.origin) / m.cell,
                          hi = (boxes[f].max() - m.origin) / m.cell;
    for (std::int64_t i = std::int64_t(std::floor(lo.x())); i <= std::int64_t(std::floor(hi.x()));
         ++i)
      for (std::int64_t j = std::int64_t(std::floor(lo.y())); j <= std::int64_t(std::floor(hi.y()));
           ++j)
        for (std::int64_t k = std::int64_t(std::floor(lo.z()));
             k <= std::int64_t(std::floor(hi.z())); ++k)
          m.grid[(i & 0x1fffff) | ((j & 0x1fffff) << 21) | ((k & 0x1fffff) << 42)].push_back(f);
  }
}

ShellProjection::~ShellProjection() = default;

std::optional<PrismPoint> ShellProjection::locate(const Eigen::Vector3d& p) const {
  const Impl& m = *m_impl;
  auto it = m.grid.find(m.key(p));
  if (it == m.grid.end()) return std::nullopt;
  for (int f : it->second) {
    if (!m.boxes[f].contains(p)) continue;  // exact: the box of the corners holds the prism
    const Eigen::Vector3i F = m.shell.F.row(f);
    std::array<Eigen::Vector3d, 3> b, mid, t;
    for (int k = 0; k < 3; ++k) {
      b[k] = m.shell.base.row(F[k]);
      mid[k] = m.shell.mid.row(F[k]);
      t[k] = m.shell.top.row(F[k]);
    }
    if (const auto q = locate_in_prism(F, b, mid, t, p)) return PrismPoint{f, q->u, q->v, q->h};
  }
  return std::nullopt;
}

Eigen::Vector3d ShellProjection::point(const PrismPoint& q) const {
  const Impl& m = *m_impl;
  const bool type_a = is_type_a(Eigen::Vector3i(m.shell.F.row(q.face)));
  const int half = q.h < 0 ? 0 : 1;
  // Points of the fiber on the 4 rising facets and their heights: the PL map is linear in h
  // along each segment between consecutive facets.
  const auto& facets = rising_facets(type_a);
  Eigen::Vector3d prev;
  double prev_h = 0;
  for (int i = 0; i < 4; ++i) {
    const auto& fc = facets[i];
    std::array<int, 3> sorted = {fc[0], fc[1], fc[2]};
    std::sort(sorted.begin(), sorted.end(), [](int a, int b) { return a % 3 < b % 3; });
    const double w[3] = {1 - q.u - q.v, q.u, q.v};
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    double h = 0;
    for (int k = 0; k < 3; ++k) {
      x += w[k] * m.corner(q.face, half, sorted[k]);
      h += w[k] * ((sorted[k] < 3 ? -1.0 : 0.0) + half);
    }
    if (i > 0 && q.h <= h + 1e-15) {
      const double s = h > prev_h ? (q.h - prev_h) / (h - prev_h) : 0.0;
      return prev + std::clamp(s, 0.0, 1.0) * (x - prev);
    }
    prev = x;
    prev_h = h;
  }
  return prev;
}

std::array<Eigen::Vector3d, 7> ShellProjection::fiber(int face, double u, double v) const {
  const Impl& m = *m_impl;
  const bool type_a = is_type_a(Eigen::Vector3i(m.shell.F.row(face)));
  const double w[3] = {1 - u - v, u, v};
  std::array<Eigen::Vector3d, 7> out;
  int n = 0;
  for (int half = 0; half < 2; ++half)
    for (int i = half; i < 4; ++i) {  // the mid facet of half 1 is the top facet of half 0
      std::array<int, 3> sorted = rising_facets(type_a)[i];
      std::sort(sorted.begin(), sorted.end(), [](int a, int b) { return a % 3 < b % 3; });
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) x += w[k] * m.corner(face, half, sorted[k]);
      out[n++] = x;
    }
  return out;
}

std::optional<SurfacePoint> ShellProjection::project(const PrismPoint& q) const {
  const Impl& m = *m_impl;
  const auto fiber = this->fiber(q.face, q.u, q.v);
  // Walk the fiber from the middle outwards: the input crosses it near h = 0.
  const int mid = 3;
  for (int d = 0; d < 3; ++d)
    for (int s : {-1, 1}) {
      const int a = s < 0 ? mid - d : mid + d, b = a + s;
      if (b < 0 || b >= int(fiber.size())) continue;
      Eigen::Vector3d bary;
      const int f = m.input.segment_hit(fiber[a], fiber[b], bary);
      if (f < 0) continue;
      SurfacePoint r;
      r.face = f;
      r.bary = bary;
      for (int k = 0; k < 3; ++k)
        r.position += bary[k] * Eigen::Vector3d(m.input.V().row(m.input.F()(f, k)));
      return r;
    }
  return std::nullopt;
}

std::optional<SurfacePoint> ShellProjection::project(const Eigen::Vector3d& p) const {
  const auto q = locate(p);
  if (!q) return std::nullopt;
  return project(*q);
}

std::optional<PrismPoint> ShellProjection::unproject(const Eigen::Vector3d& x) const {
  return locate(x);
}

std::vector<int> ShellProjection::prisms_in_box(const Eigen::Vector3d& lo,
                                                const Eigen::Vector3d& hi) const {
  const Impl& m = *m_impl;
  const Eigen::AlignedBox3d box(lo, hi);
  std::vector<int> out;
  const Eigen::Vector3d a = ((lo - m.origin) / m.cell).array().floor(),
                        b = ((hi - m.origin) / m.cell).array().floor();
  const double cells = (b - a + Eigen::Vector3d::Ones()).prod();
  if (!(cells <= double(m.boxes.size()))) {  // a box larger than the shell's cells: scan
    for (int f = 0; f < int(m.boxes.size()); ++f)
      if (m.boxes[f].intersects(box)) out.push_back(f);
    return out;
  }
  for (std::int64_t i = std::int64_t(a.x()); i <= std::int64_t(b.x()); ++i)
    for (std::int64_t j = std::int64_t(a.y()); j <= std::int64_t(b.y()); ++j)
      for (std::int64_t k = std::int64_t(a.z()); k <= std::int64_t(b.z()); ++k) {
        auto it = m.grid.find((i & 0x1fffff) | ((j & 0x1fffff) << 21) | ((k & 0x1fffff) << 42));
        if (it == m.grid.end()) continue;
        for (int f : it->second)
          if (m.boxes[f].intersects(box)) out.push_back(f);
      }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

const Shell& ShellProjection::shell() const { return m_impl->shell; }

bool ShellProjection::is_section(const SurfaceMesh& m) const {
  return SectionChecker(*this).check(m).is_section();
}

}  // namespace curvefem::meshing::shell
