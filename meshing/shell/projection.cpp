#include "meshing/shell/projection.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_map>

#include "meshing/shell/local_sheets.hpp"
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
  std::optional<LocalSheets> sheets;       // a locally injective shell's (local_sheets.hpp)
  std::vector<std::vector<int>> sheet_of;  // per prism, with `sheets`

  // With a reference copy (Shell::reference) the fibers cross that copy, and each crossing is
  // reported as the input point with the same face and barycentric coordinates.
  Impl(const Shell& s, const SurfaceMesh& in) : shell(s), input(in.V, in.F, s.reference) {
    if (s.local_sheets) sheets.emplace(input);
  }
  // The local sheet of prism f: the input faces its fibers may cross.
  const std::vector<int>& local(int f) const { return sheet_of[std::size_t(f)]; }

  // Corner c (0..5) of half `half` (0: base→mid, 1: mid→top) of face f, rotated order.
  Eigen::Vector3d corner(int f, int half, int c) const {
    const Eigen::Vector3i F = shell.F.row(f);
    const int r = min_rotation(F);
    const int v = F[(r + c % 3) % 3];
    const Eigen::MatrixXd& lower = half == 0 ? shell.base : shell.mid;
    const Eigen::MatrixXd& upper = half == 0 ? shell.mid : shell.top;
    return c < 3 ? Eigen::Vector3d(lower.row(v)) : Eigen::Vector3d(upper.row(v));
  }
  // A pinched vertex: a singular vertex, whose pillar has zero length (base = mid = top).
  bool pinched(int v) const {
    return shell.base.row(v) == shell.mid.row(v) && shell.top.row(v) == shell.mid.row(v);
  }
  // The fiber points on the rising facets at barycentric weights w of the rotated face.
  std::array<Eigen::Vector3d, 7> fiber(int f, const std::array<double, 3>& w) const;
  // The input point of the zero-length fiber at pinch point x, or nullopt (x off the input).
  std::optional<SurfacePoint> at_pinch(const Eigen::Vector3d& x,
                                       const std::vector<int>* among = nullptr) const;
  // The input point on a fiber near pinched corner s of face f (weights w) that the search on
  // the rounded fiber missed.
  std::optional<SurfacePoint> near_pinch(int f, int s, const std::array<double, 3>& w,
                                         const std::vector<int>* among = nullptr) const;
  SurfacePoint surface_point(int face, const Eigen::Vector3d& bary) const {
    SurfacePoint r;
    r.face = face;
    r.bary = bary;
    for (int k = 0; k < 3; ++k)
      r.position += bary[k] * Eigen::Vector3d(input.V().row(input.F()(face, k)));
    return r;
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
  if (m.sheets) {
    m.sheet_of.resize(std::size_t(nf));
    tbb::parallel_for(0, nf, [&](int f) {
      m.sheet_of[std::size_t(f)] =
          m.sheets->sheet({shell.face_parent[std::size_t(f)]}, boxes[std::size_t(f)]);
    });
  }
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
  return locate_on(p, -1);
}

std::optional<PrismPoint> ShellProjection::locate_on(const Eigen::Vector3d& p,
                                                     int input_face) const {
  const Impl& m = *m_impl;
  auto it = m.grid.find(m.key(p));
  if (it == m.grid.end()) return std::nullopt;
  for (int f : it->second) {
    if (!m.boxes[f].contains(p)) continue;  // exact: the box of the corners holds the prism
    if (input_face >= 0 && m.sheets &&
        !std::binary_search(m.local(f).begin(), m.local(f).end(), input_face))
      continue;
    const Eigen::Vector3i F = m.shell.F.row(f);
    // A pinch point is the whole pillar of its corner: exactly that corner, at h = 0.
    const int r = min_rotation(F);
    for (int c = 0; c < 3; ++c) {
      const int v = F[(r + c) % 3];
      if (m.pinched(v) && m.shell.mid.row(v) == p.transpose())
        return PrismPoint{f, c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0, 0.0};
    }
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

std::array<Eigen::Vector3d, 7> ShellProjection::Impl::fiber(int f,
                                                            const std::array<double, 3>& w) const {
  return fiber_points(is_type_a(Eigen::Vector3i(shell.F.row(f))), w,
                      [&](int half, int c) { return corner(f, half, c); });
}

std::array<Eigen::Vector3d, 7> ShellProjection::fiber(int face, double u, double v) const {
  return m_impl->fiber(face, {1 - u - v, u, v});
}

namespace {

// Barycentric coordinates of x, a point of the plane of tri (floating-point solve).
Eigen::Vector3d barycentric(const std::array<Eigen::Vector3d, 3>& tri, const Eigen::Vector3d& x) {
  const Eigen::Vector3d n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
  const double area = n.squaredNorm();
  Eigen::Vector3d w;
  w[1] = n.dot((x - tri[0]).cross(tri[2] - tri[0])) / area;
  w[2] = n.dot((tri[1] - tri[0]).cross(x - tri[0])) / area;
  w[0] = 1.0 - w[1] - w[2];
  return w;
}
}  // namespace

// A pinch point lies on the input (separation allows contact there only): on an input vertex,
// or inside an input face or edge. The face of smallest id containing it, exactly; x itself when
// it is a corner of that face. A pinch point off the surface by rounding only (a singular pinch
// split's rounded midpoint, a section missing it by rounding) gets the closest surface point.
std::optional<SurfacePoint> ShellProjection::Impl::at_pinch(const Eigen::Vector3d& x,
                                                            const std::vector<int>* among) const {
  const std::vector<int> star = input.faces_containing(x, among);
  if (star.empty()) {
    Eigen::Vector3d closest;
    const int f = input.closest_face(x, closest);
    if (f < 0 || (among && !std::binary_search(among->begin(), among->end(), f)) ||
        (closest - x).cwiseAbs().maxCoeff() >
            16 * std::numeric_limits<double>::epsilon() * x.cwiseAbs().maxCoeff())
      return std::nullopt;
    return surface_point(f, barycentric(input.face_triangle(f), closest));
  }
  const auto tri = input.face_triangle(star.front());
  for (int k = 0; k < 3; ++k)
    if (tri[k] == x) return surface_point(star.front(), Eigen::Vector3d::Unit(k));
  return surface_point(star.front(), barycentric(tri, x));
}

// Near a pinched corner s (pinch point x) every fiber point is x + t (z − x): the fiber is the
// image, under the homothety of centre x and ratio t = 1 − w_s, of the fiber z at the point of
// the opposite edge with weights w_k / t. For t within rounding of 0 the computed fiber has
// length ~1e-16 and the exact search on it can miss the input; z has the length of a pillar.
// The input near x is the fan of the faces containing x, split at x into wedges (x; a, b) over
// their edges (a, b): a cone with apex x, invariant under the homothety. So z crosses a wedge at
// x + α (a − x) + β (b − x) exactly where the fiber crosses it at x + t α (a − x) + t β (b − x),
// which is a point of the face as long as t (α + β) ≤ 1. The crossing is decided by exact
// predicates on z (segment_crosses_wedge), then solved for (α, β).
std::optional<SurfacePoint> ShellProjection::Impl::near_pinch(int f, int s,
                                                              const std::array<double, 3>& w,
                                                              const std::vector<int>* among) const {
  const Eigen::Vector3i F = shell.F.row(f);
  const Eigen::Vector3d x = shell.mid.row(F[(min_rotation(F) + s) % 3]).transpose();
  std::array<double, 3> c{std::max(w[0], 0.0), std::max(w[1], 0.0), std::max(w[2], 0.0)};
  const double rest = c[(s + 1) % 3] + c[(s + 2) % 3];
  if (!(rest > 0)) return at_pinch(x, among);
  const double t = rest / (rest + c[s]);
  std::array<double, 3> wz{0, 0, 0};
  for (int k : {(s + 1) % 3, (s + 2) % 3}) wz[k] = c[k] / rest;
  const auto z = fiber(f, wz);

  const std::vector<int> star = input.faces_containing(x, among);
  if (star.empty()) {
    // x is off the input by rounding: only a fiber that is x up to rounding maps to the input
    // point closest to x.
    double extent = 0, scale = x.cwiseAbs().maxCoeff();
    for (const auto& p : z) {
      extent = std::max(extent, t * (p - x).cwiseAbs().maxCoeff());
      scale = std::max(scale, p.cwiseAbs().maxCoeff());
    }
    if (extent > 16 * std::numeric_limits<double>::epsilon() * scale) return std::nullopt;
    return at_pinch(x, among);
  }
  struct Wedge {
    int face, k;  // the wedge (x; corner k, corner k + 1) of that face
    std::array<Eigen::Vector3d, 3> tri;
    Eigen::Vector3d pi;  // barycentric coordinates of x in the face
  };
  std::vector<Wedge> wedges;
  for (int g : star) {
    const auto tri = input.face_triangle(g);
    Eigen::Vector3d pi = barycentric(tri, x);
    for (int k = 0; k < 3; ++k)
      if (tri[k] == x) pi = Eigen::Vector3d::Unit(k);
    for (int k = 0; k < 3; ++k)
      if (tri[k] != x && tri[(k + 1) % 3] != x) wedges.push_back({g, k, tri, pi});
  }
  for (const auto& seg : k_fiber_walk) {
    const Eigen::Vector3d &p = z[seg[0]], &q = z[seg[1]];
    std::optional<SurfacePoint> best;
    double best_tau = std::numeric_limits<double>::infinity();
    for (const Wedge& e : wedges) {
      const Eigen::Vector3d &a = e.tri[e.k], &b = e.tri[(e.k + 1) % 3];
      if (!segment_crosses_wedge(p, q, x, a, b)) continue;
      const Eigen::Vector3d n = (a - x).cross(b - x);
      const double den = n.dot(q - p);
      const double tau = den != 0 ? std::clamp(n.dot(x - p) / den, 0.0, 1.0) : 0.0;
      if (tau >= best_tau) continue;
      const Eigen::Vector3d d = p + tau * (q - p) - x;
      const double alpha = std::max(n.dot(d.cross(b - x)) / n.squaredNorm(), 0.0),
                   beta = std::max(n.dot((a - x).cross(d)) / n.squaredNorm(), 0.0);
      if (t * (alpha + beta) > 1) continue;  // beyond this face: z meets the cone, not the input
      Eigen::Vector3d bary = (1 - t * (alpha + beta)) * e.pi;
      bary[e.k] += t * alpha;
      bary[(e.k + 1) % 3] += t * beta;
      best = surface_point(e.face, bary);
      best_tau = tau;
    }
    if (best) return best;
  }
  return std::nullopt;
}

std::optional<SurfacePoint> ShellProjection::project(const PrismPoint& q) const {
  const Impl& m = *m_impl;
  const std::array<double, 3> w{1 - q.u - q.v, q.u, q.v};
  // The pinched corner of the face (at most one after pinch splitting; the heaviest otherwise).
  const Eigen::Vector3i F = m.shell.F.row(q.face);
  const int r = min_rotation(F);
  int s = -1;
  for (int c = 0; c < 3; ++c)
    if (m.pinched(F[(r + c) % 3]) && (s < 0 || w[c] > w[s])) s = c;
  // A locally injective shell's fibers cross the prism's local sheet only.
  const std::vector<int>* among = m.sheets ? &m.local(q.face) : nullptr;
  // At the pinched corner itself the fiber is the pinch point.
  if (s >= 0 && w[(s + 1) % 3] <= 0 && w[(s + 2) % 3] <= 0)
    return m.at_pinch(m.corner(q.face, 1, s), among);
  const auto fiber = m.fiber(q.face, w);
  for (const auto& seg : k_fiber_walk) {
    Eigen::Vector3d bary;
    const int f = m.input.segment_hit(fiber[seg[0]], fiber[seg[1]], bary, among);
    if (f >= 0) return m.surface_point(f, bary);
  }
  // Rounding can hide the crossing of a fiber shrunk toward a pinch point.
  if (s >= 0) return m.near_pinch(q.face, s, w, among);
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

std::optional<PrismPoint> ShellProjection::unproject(const Eigen::Vector3d& x,
                                                     int input_face) const {
  return locate_on(x, input_face);
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

const Eigen::MatrixXd& ShellProjection::reference_vertices() const {
  return m_impl->input.reference_V();
}

}  // namespace curvefem::meshing::shell
