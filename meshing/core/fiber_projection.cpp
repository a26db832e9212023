#include "meshing/core/fiber_projection.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "meshing/core/error.hpp"
#include "meshing/core/exact_predicates.hpp"
#include "meshing/core/prism_split.hpp"

namespace curvefem {
namespace {

constexpr double k_eps = std::numeric_limits<double>::epsilon();

// Barycentric coordinates of x, a point of the plane of tri (the solve of projection.cpp).
Eigen::Vector3d barycentric(const std::array<Eigen::Vector3d, 3>& tri, const Eigen::Vector3d& x) {
  const Eigen::Vector3d n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
  const double area = n.squaredNorm();
  Eigen::Vector3d w;
  w[1] = n.dot((x - tri[0]).cross(tri[2] - tri[0])) / area;
  w[2] = n.dot((tri[1] - tri[0]).cross(x - tri[0])) / area;
  w[0] = 1.0 - w[1] - w[2];
  return w;
}

Eigen::Vector3d closest_on_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                   const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return a + t * d;
}

// The point of the closed (non-degenerate) triangle closest to p.
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p,
                                    const std::array<Eigen::Vector3d, 3>& tri) {
  const Eigen::Vector3d n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
  const Eigen::Vector3d q = p - n * (n.dot(p - tri[0]) / n.squaredNorm());
  if (barycentric(tri, q).minCoeff() >= 0) return q;
  Eigen::Vector3d best = closest_on_segment(p, tri[0], tri[1]);
  for (int k = 1; k < 3; ++k) {
    const Eigen::Vector3d c = closest_on_segment(p, tri[k], tri[(k + 1) % 3]);
    if ((c - p).squaredNorm() < (best - p).squaredNorm()) best = c;
  }
  return best;
}

// Does the closed segment [p, q] cross the plane of the wedge {apex + α(a − apex) + β(b − apex) :
// α, β ≥ 0} at a point of the wedge? meshing/shell's segment_crosses_wedge, with the same exact
// predicates.
bool segment_crosses_wedge(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                           const Eigen::Vector3d& apex, const Eigen::Vector3d& a,
                           const Eigen::Vector3d& b) {
  if (exact::collinear(apex, a, b)) return false;
  const int sp = exact::orient3d(apex, a, b, p), sq = exact::orient3d(apex, a, b, q);
  if ((sp == 0 && sq == 0) || sp * sq > 0) return false;
  const int dir = sq != 0 ? sq : -sp;
  return exact::orient3d(p, q, apex, a) * dir >= 0 && exact::orient3d(p, q, b, apex) * dir >= 0;
}

}  // namespace

FiberProjection::FiberProjection(ShellFibers fibers, const SurfaceMesh& input)
    : m_fibers(std::move(fibers)),
      m_input_V(input.V),
      m_input_F(input.F),
      m_V(input.V),
      m_reference(input.V),
      m_F(input.F) {
  validate_structure(m_fibers, input.num_vertices(), input.num_faces());
  if (m_fibers.refined()) {
    m_V.resize(input.V.rows() + m_fibers.surface_points.rows(), 3);
    m_V << input.V, m_fibers.surface_points;
    m_reference = m_V;
    m_F = m_fibers.surface_faces;
  }
  for (std::size_t i = 0; i < m_fibers.reference_vertices.size(); ++i)
    m_reference.row(m_fibers.reference_vertices[i]) =
        m_fibers.reference_positions.row(Eigen::Index(i));
  m_lo.resize(std::size_t(m_F.rows()));
  m_hi.resize(std::size_t(m_F.rows()));
  for (int t = 0; t < m_F.rows(); ++t) {
    const auto tri = triangle(t);
    m_lo[std::size_t(t)] = tri[0].cwiseMin(tri[1]).cwiseMin(tri[2]);
    m_hi[std::size_t(t)] = tri[0].cwiseMax(tri[1]).cwiseMax(tri[2]);
  }
}

std::array<Eigen::Vector3d, 3> FiberProjection::triangle(int t) const {
  return {m_reference.row(m_F(t, 0)).transpose(), m_reference.row(m_F(t, 1)).transpose(),
          m_reference.row(m_F(t, 2)).transpose()};
}

FiberCrossing FiberProjection::input_point(int t, const Eigen::Vector3d& bary) const {
  FiberCrossing r;
  r.face = t;
  r.bary = bary;
  if (m_fibers.refined()) {  // refined face t -> its input face
    r.face = m_fibers.surface_parent[std::size_t(t)];
    r.bary.setZero();
    for (int k = 0; k < 3; ++k)
      r.bary += bary[k] * m_fibers.surface_bary.row(t).segment<3>(3 * k).transpose();
  }
  for (int k = 0; k < 3; ++k)
    r.position += r.bary[k] * Eigen::Vector3d(m_input_V.row(m_input_F(r.face, k)));
  return r;
}

std::array<Eigen::Vector3d, 7> FiberProjection::fiber_at(int f,
                                                         const std::array<double, 3>& w) const {
  const Eigen::Vector3i F = m_fibers.faces.row(f);
  return fiber_points(is_type_a(F), w, [&](int half, int c) {
    const Eigen::MatrixXd& lower = half == 0 ? m_fibers.base : m_fibers.mid;
    const Eigen::MatrixXd& upper = half == 0 ? m_fibers.mid : m_fibers.top;
    const int v = F[c % 3];
    return c < 3 ? Eigen::Vector3d(lower.row(v)) : Eigen::Vector3d(upper.row(v));
  });
}

std::array<Eigen::Vector3d, 7> FiberProjection::fiber(int face, double u, double v) const {
  return fiber_at(face, {1 - u - v, u, v});
}

// The crossing of segment [a, b] with the candidate faces of prism f closest to a: the faces the
// closed segment meets, decided exactly (the decisions of meshing/shell's segment_hit, which
// uses CGAL's exact predicates), then the parameter and barycentric solves of that function
// repeated operation for operation, so the same face gives the same bits.
std::optional<FiberCrossing> FiberProjection::segment_hit(int f, const Eigen::Vector3d& a,
                                                          const Eigen::Vector3d& b) const {
  if (a == b) return std::nullopt;
  const Eigen::Vector3d lo = a.cwiseMin(b), hi = a.cwiseMax(b);
  int best = -1;
  double best_t = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best_w;
  for (const int t : m_fibers.candidates(f)) {
    const Eigen::Vector3d &tlo = m_lo[std::size_t(t)], &thi = m_hi[std::size_t(t)];
    if ((tlo.array() > hi.array()).any() || (thi.array() < lo.array()).any()) continue;
    const auto tri = triangle(t);
    const Eigen::Vector3d &p0 = tri[0], &p1 = tri[1], &p2 = tri[2];
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    const double area = n.squaredNorm();
    if (!(area > 0) || !exact::segment_meets_triangle(a, b, p0, p1, p2)) continue;
    const double denom = n.dot(b - a);
    double tt = 0.0;
    if (std::abs(denom) > 0) tt = std::clamp(n.dot(p0 - a) / denom, 0.0, 1.0);
    if (tt >= best_t) continue;
    const Eigen::Vector3d x = a + tt * (b - a);
    Eigen::Vector3d w;
    w[1] = n.dot((x - p0).cross(p2 - p0)) / area;
    w[2] = n.dot((p1 - p0).cross(x - p0)) / area;
    w[0] = 1.0 - w[1] - w[2];
    best = t;
    best_t = tt;
    best_w = w;
  }
  if (best < 0) return std::nullopt;
  return input_point(best, best_w);
}

// Is x on the closed reference triangle of input face t (exactly, as the shell projection's
// faces_containing decides)? Degenerate triangles contain nothing.
bool FiberProjection::contains(int t, const Eigen::Vector3d& x) const {
  const auto tri = triangle(t);
  return exact::triangle_contains(tri[0], tri[1], tri[2], x);
}

std::vector<int> FiberProjection::star(int f, const Eigen::Vector3d& x) const {
  std::vector<int> out;
  for (const int t : m_fibers.candidates(f))
    if ((m_lo[std::size_t(t)].array() <= x.array()).all() &&
        (x.array() <= m_hi[std::size_t(t)].array()).all() && contains(t, x))
      out.push_back(t);
  return out;
}

// A pinch point lies on the input: the face of smallest id containing it; x itself when it is a
// corner of that face; the closest input point when x is off the input by rounding only.
std::optional<FiberCrossing> FiberProjection::at_pinch(int f, const Eigen::Vector3d& x) const {
  const std::vector<int> st = star(f, x);
  if (st.empty()) {
    int best = -1;
    Eigen::Vector3d closest;
    double best_d = std::numeric_limits<double>::infinity();
    for (const int t : m_fibers.candidates(f)) {
      const auto tri = triangle(t);
      if (!((tri[1] - tri[0]).cross(tri[2] - tri[0]).squaredNorm() > 0)) continue;
      const Eigen::Vector3d c = closest_on_triangle(x, tri);
      const double d = (c - x).squaredNorm();
      if (d < best_d) best = t, best_d = d, closest = c;
    }
    if (best < 0 || (closest - x).cwiseAbs().maxCoeff() > 16 * k_eps * x.cwiseAbs().maxCoeff())
      return std::nullopt;
    return input_point(best, barycentric(triangle(best), closest));
  }
  const auto tri = triangle(st.front());
  for (int k = 0; k < 3; ++k)
    if (tri[k] == x) return input_point(st.front(), Eigen::Vector3d::Unit(k));
  return input_point(st.front(), barycentric(tri, x));
}

// Near pinched corner s (pinch point x) the fiber is the image of the fiber z at the opposite
// edge point with weights w_k / t under the homothety of centre x and ratio t = 1 − w_s; the
// input near x is a cone with apex x (the fan of the faces containing it, split into wedges), so
// z crosses it where the fiber does, scaled by 1/t (projection.cpp, near_pinch).
std::optional<FiberCrossing> FiberProjection::near_pinch(int f, int s,
                                                         const std::array<double, 3>& w) const {
  const Eigen::Vector3i F = m_fibers.faces.row(f);
  const Eigen::Vector3d x = m_fibers.mid.row(F[s]).transpose();
  std::array<double, 3> c{std::max(w[0], 0.0), std::max(w[1], 0.0), std::max(w[2], 0.0)};
  const double rest = c[(s + 1) % 3] + c[(s + 2) % 3];
  if (!(rest > 0)) return at_pinch(f, x);
  const double t = rest / (rest + c[s]);
  std::array<double, 3> wz{0, 0, 0};
  for (int k : {(s + 1) % 3, (s + 2) % 3}) wz[k] = c[k] / rest;
  const auto z = fiber_at(f, wz);

  const std::vector<int> st = star(f, x);
  if (st.empty()) {
    double extent = 0, scale = x.cwiseAbs().maxCoeff();
    for (const auto& p : z) {
      extent = std::max(extent, t * (p - x).cwiseAbs().maxCoeff());
      scale = std::max(scale, p.cwiseAbs().maxCoeff());
    }
    if (extent > 16 * k_eps * scale) return std::nullopt;
    return at_pinch(f, x);
  }
  struct Wedge {
    int face, k;  // the wedge (x; corner k, corner k + 1) of that face
    std::array<Eigen::Vector3d, 3> tri;
    Eigen::Vector3d pi;  // barycentric coordinates of x in the face
  };
  std::vector<Wedge> wedges;
  for (int g : st) {
    const auto tri = triangle(g);
    Eigen::Vector3d pi = barycentric(tri, x);
    for (int k = 0; k < 3; ++k)
      if (tri[k] == x) pi = Eigen::Vector3d::Unit(k);
    for (int k = 0; k < 3; ++k)
      if (tri[k] != x && tri[(k + 1) % 3] != x) wedges.push_back({g, k, tri, pi});
  }
  for (const auto& seg : k_fiber_walk) {
    const Eigen::Vector3d &p = z[seg[0]], &q = z[seg[1]];
    std::optional<FiberCrossing> best;
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
      best = input_point(e.face, bary);
      best_tau = tau;
    }
    if (best) return best;
  }
  return std::nullopt;
}

std::optional<FiberCrossing> FiberProjection::project(int face, double u, double v) const {
  if (face < 0 || face >= m_fibers.num_prisms()) return std::nullopt;
  const std::array<double, 3> w{1 - u - v, u, v};
  // The pinched corner of the face (at most one after pinch splitting; the heaviest otherwise).
  const Eigen::Vector3i F = m_fibers.faces.row(face);
  int s = -1;
  for (int c = 0; c < 3; ++c)
    if (m_fibers.pinched(F[c]) && (s < 0 || w[c] > w[s])) s = c;
  // At the pinched corner itself the fiber is the pinch point.
  if (s >= 0 && w[(s + 1) % 3] <= 0 && w[(s + 2) % 3] <= 0)
    return at_pinch(face, m_fibers.mid.row(F[s]).transpose());
  const auto z = fiber_at(face, w);
  for (const auto& seg : k_fiber_walk)
    if (auto hit = segment_hit(face, z[seg[0]], z[seg[1]])) return hit;
  // Rounding can hide the crossing of a fiber shrunk toward a pinch point.
  if (s >= 0) return near_pinch(face, s, w);
  return std::nullopt;
}

}  // namespace curvefem
