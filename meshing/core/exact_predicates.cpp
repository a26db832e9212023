#include "meshing/core/exact_predicates.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace curvefem::exact {
namespace {

constexpr double k_eps = std::numeric_limits<double>::epsilon() / 2;  // unit roundoff

// Expansion arithmetic (Shewchuk, "Adaptive precision floating-point arithmetic and fast robust
// geometric predicates", 1997): a number is the exact sum of nonoverlapping doubles in order of
// increasing magnitude; zeros are dropped. The sign of the sum is that of the last component.
using Expansion = std::vector<double>;

void two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bv = s - a, av = s - bv;
  e = (a - av) + (b - bv);
}

Expansion grow(const Expansion& e, double b) {
  Expansion h;
  h.reserve(e.size() + 1);
  double q = b;
  for (const double c : e) {
    double s, err;
    two_sum(q, c, s, err);
    if (err != 0) h.push_back(err);
    q = s;
  }
  if (q != 0) h.push_back(q);
  return h;
}

Expansion sum(Expansion e, const Expansion& f) {
  for (const double c : f) e = grow(e, c);
  return e;
}

Expansion negate(Expansion e) {
  for (double& c : e) c = -c;
  return e;
}

Expansion scale(const Expansion& e, double b) {
  Expansion out;
  for (const double c : e) {
    const double p = c * b;
    const double err = std::fma(c, b, -p);  // exact: p + err = c b
    Expansion term;
    if (err != 0) term.push_back(err);
    if (p != 0) term.push_back(p);
    out = sum(std::move(out), term);
  }
  return out;
}

Expansion mul(const Expansion& e, const Expansion& f) {
  Expansion out;
  for (const double c : f) out = sum(std::move(out), scale(e, c));
  return out;
}

Expansion diff(double b, double a) {  // b − a exactly
  double s, err;
  two_sum(b, -a, s, err);
  Expansion e;
  if (err != 0) e.push_back(err);
  if (s != 0) e.push_back(s);
  return e;
}

int sign(const Expansion& e) { return e.empty() ? 0 : (e.back() > 0 ? 1 : -1); }

int orient3d_exact(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Eigen::Vector3d& d) {
  Expansion x[3], y[3], z[3];
  for (int i = 0; i < 3; ++i) {
    x[i] = diff(b[i], a[i]);
    y[i] = diff(c[i], a[i]);
    z[i] = diff(d[i], a[i]);
  }
  Expansion det;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const Expansion minor = sum(mul(y[j], z[k]), negate(mul(y[k], z[j])));
    det = sum(std::move(det), mul(x[i], minor));
  }
  return sign(det);
}

int orient2d_exact(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const Expansion l = mul(diff(b[0], a[0]), diff(c[1], a[1]));
  const Expansion r = mul(diff(b[1], a[1]), diff(c[0], a[0]));
  return sign(sum(l, negate(r)));
}

// The coordinates of x without axis k (a projection that is one-to-one on a plane whose normal
// has a nonzero k-th component).
Eigen::Vector2d drop(const Eigen::Vector3d& x, int k) { return {x[(k + 1) % 3], x[(k + 2) % 3]}; }

// An axis along which the projection of the non-degenerate triangle (a, b, c) keeps its area, or
// -1 for a degenerate triangle.
int projection_axis(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // The k-th component of (b − a) × (c − a) is the 2-D orientation without axis k; try the
  // largest one in floating point first.
  const Eigen::Vector3d n = (b - a).cross(c - a).cwiseAbs();
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int i, int j) { return n[i] > n[j]; });
  for (const int k : order)
    if (orient2d(drop(a, k), drop(b, k), drop(c, k)) != 0) return k;
  return -1;
}

// Is x in the closed 2-D triangle (a, b, c) of orientation s ≠ 0?
bool in_triangle_2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                    int s, const Eigen::Vector2d& x) {
  return orient2d(a, b, x) * s >= 0 && orient2d(b, c, x) * s >= 0 && orient2d(c, a, x) * s >= 0;
}

// x on the closed segment [u, v], given collinear.
bool between(const Eigen::Vector2d& u, const Eigen::Vector2d& v, const Eigen::Vector2d& x) {
  return std::min(u[0], v[0]) <= x[0] && x[0] <= std::max(u[0], v[0]) &&
         std::min(u[1], v[1]) <= x[1] && x[1] <= std::max(u[1], v[1]);
}

bool segments_meet_2d(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& u,
                      const Eigen::Vector2d& v) {
  const int d1 = orient2d(p, q, u), d2 = orient2d(p, q, v), d3 = orient2d(u, v, p),
            d4 = orient2d(u, v, q);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && between(p, q, u)) || (d2 == 0 && between(p, q, v)) ||
         (d3 == 0 && between(u, v, p)) || (d4 == 0 && between(u, v, q));
}

}  // namespace

int orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d) {
  const Eigen::Vector3d x = b - a, y = c - a, z = d - a;
  const double m0 = y[1] * z[2] - y[2] * z[1], m1 = y[2] * z[0] - y[0] * z[2],
               m2 = y[0] * z[1] - y[1] * z[0];
  const double det = x[0] * m0 + x[1] * m1 + x[2] * m2;
  const double perm = std::abs(x[0]) * (std::abs(y[1] * z[2]) + std::abs(y[2] * z[1])) +
                      std::abs(x[1]) * (std::abs(y[2] * z[0]) + std::abs(y[0] * z[2])) +
                      std::abs(x[2]) * (std::abs(y[0] * z[1]) + std::abs(y[1] * z[0]));
  // Shewchuk's bound (7 + 56 u) u · permanent for rounded differences, rounded up.
  const double bound = 8 * k_eps * perm;
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return orient3d_exact(a, b, c, d);
}

int orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const double l = (b[0] - a[0]) * (c[1] - a[1]), r = (b[1] - a[1]) * (c[0] - a[0]);
  const double det = l - r;
  const double bound = 4 * k_eps * (std::abs(l) + std::abs(r));  // (3 + 16 u) u, rounded up
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return orient2d_exact(a, b, c);
}

bool collinear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return projection_axis(a, b, c) < 0;
}

bool triangle_contains(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& x) {
  const int k = projection_axis(a, b, c);
  if (k < 0 || orient3d(a, b, c, x) != 0) return false;
  const Eigen::Vector2d a2 = drop(a, k), b2 = drop(b, k), c2 = drop(c, k);
  return in_triangle_2d(a2, b2, c2, orient2d(a2, b2, c2), drop(x, k));
}

bool segment_meets_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                            const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c) {
  if (p == q) return false;
  const int k = projection_axis(a, b, c);
  if (k < 0) return false;
  const int sp = orient3d(a, b, c, p), sq = orient3d(a, b, c, q);
  if (sp * sq > 0) return false;
  if (sp != 0 || sq != 0) {
    // The line p q crosses the plane at one point x; det[q − p, u − p, v − p] has the sign of
    // (q − p)·n times the 2-D orientation of (u, v, x), so x is in the closed triangle iff the
    // three edge signs do not disagree.
    const int o1 = orient3d(p, q, a, b), o2 = orient3d(p, q, b, c), o3 = orient3d(p, q, c, a);
    return !((o1 > 0 || o2 > 0 || o3 > 0) && (o1 < 0 || o2 < 0 || o3 < 0));
  }
  // Coplanar: in the projection along axis k (one-to-one on the plane).
  const Eigen::Vector2d a2 = drop(a, k), b2 = drop(b, k), c2 = drop(c, k), p2 = drop(p, k),
                        q2 = drop(q, k);
  const int s = orient2d(a2, b2, c2);
  return in_triangle_2d(a2, b2, c2, s, p2) || in_triangle_2d(a2, b2, c2, s, q2) ||
         segments_meet_2d(p2, q2, a2, b2) || segments_meet_2d(p2, q2, b2, c2) ||
         segments_meet_2d(p2, q2, c2, a2);
}

}  // namespace curvefem::exact
