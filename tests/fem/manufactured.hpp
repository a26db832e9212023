// Manufactured solutions with analytic derivatives for the fem tests.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace curvefem::test {

/// The 3-D Franke-type function of the thesis (§5.4.4): value, gradient, Laplacian.
struct Franke {
  struct Term {
    double c;
    // g(x) = Σ_i a_i (9 x_i - b_i)^2 (+ linear terms in lin), see value().
  };
  static double term(int t, const Eigen::Vector3d& x, Eigen::Vector3d* grad, double* lap) {
    const double X = 9 * x[0], Y = 9 * x[1], Z = 9 * x[2];
    double g;
    Eigen::Vector3d dg;
    double ddg, c;
    switch (t) {
      case 0:
        c = 0.75;
        g = -((X - 2) * (X - 2) + (Y - 2) * (Y - 2) + (Z - 2) * (Z - 2)) / 4;
        dg = -4.5 * Eigen::Vector3d(X - 2, Y - 2, Z - 2);
        ddg = -3 * 81.0 / 2;
        break;
      case 1:
        c = 0.75;
        g = -(X + 1) * (X + 1) / 49 - (Y + 1) / 10 - (Z + 1) / 10;
        dg = Eigen::Vector3d(-18 * (X + 1) / 49, -0.9, -0.9);
        ddg = -162.0 / 49;
        break;
      case 2:
        c = 0.5;
        g = -((X - 7) * (X - 7) + (Y - 3) * (Y - 3) + (Z - 5) * (Z - 5)) / 4;
        dg = -4.5 * Eigen::Vector3d(X - 7, Y - 3, Z - 5);
        ddg = -3 * 81.0 / 2;
        break;
      default:
        c = -0.2;
        g = -((X - 4) * (X - 4) + (Y - 7) * (Y - 7) + (Z - 5) * (Z - 5));
        dg = -18 * Eigen::Vector3d(X - 4, Y - 7, Z - 5);
        ddg = -3 * 162.0;
    }
    const double e = c * std::exp(g);
    if (grad) *grad += e * dg;
    if (lap) *lap += e * (dg.squaredNorm() + ddg);
    return e;
  }
  static double value(const Eigen::Vector3d& x) {
    double v = 0;
    for (int t = 0; t < 4; ++t) v += term(t, x, nullptr, nullptr);
    return v;
  }
  static Eigen::Vector3d gradient(const Eigen::Vector3d& x) {
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int t = 0; t < 4; ++t) term(t, x, &g, nullptr);
    return g;
  }
  static double laplacian(const Eigen::Vector3d& x) {
    double l = 0;
    for (int t = 0; t < 4; ++t) term(t, x, nullptr, &l);
    return l;
  }
};

/// Displacement u = Σ a_t exp(k_t · x) with the body force f = −∇·σ(u) of linear elasticity.
struct ExponentialDisplacement {
  double lambda, mu;
  Eigen::Vector3d a[2] = {{0.3, -0.2, 0.1}, {-0.1, 0.25, 0.2}};
  Eigen::Vector3d k[2] = {{0.8, -0.5, 0.3}, {-0.4, 0.6, 0.9}};
  Eigen::Vector3d value(const Eigen::Vector3d& x) const {
    return a[0] * std::exp(k[0].dot(x)) + a[1] * std::exp(k[1].dot(x));
  }
  Eigen::Matrix3d gradient(const Eigen::Vector3d& x) const {  // ∂u_i/∂x_j
    return a[0] * k[0].transpose() * std::exp(k[0].dot(x)) +
           a[1] * k[1].transpose() * std::exp(k[1].dot(x));
  }
  Eigen::Vector3d body_force(const Eigen::Vector3d& x) const {
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    for (int t = 0; t < 2; ++t)
      f -= ((lambda + mu) * a[t].dot(k[t]) * k[t] + mu * k[t].squaredNorm() * a[t]) *
           std::exp(k[t].dot(x));
    return f;
  }
};

/// Least-squares slope of log(error) against log(h) over the last two levels.
inline double rate(double e_coarse, double e_fine, double h_ratio = 2.0) {
  return std::log(e_coarse / e_fine) / std::log(h_ratio);
}

/// u = exp(x/2) sin(y + z/2): −Δu = −(1/4 − 1 − 1/4) u = u (smooth, for optimal rates at every p).
struct ExpSine {
  static double value(const Eigen::Vector3d& x) {
    return std::exp(0.5 * x[0]) * std::sin(x[1] + 0.5 * x[2]);
  }
  static Eigen::Vector3d gradient(const Eigen::Vector3d& x) {
    const double e = std::exp(0.5 * x[0]), s = std::sin(x[1] + 0.5 * x[2]),
                 c = std::cos(x[1] + 0.5 * x[2]);
    return Eigen::Vector3d(0.5 * e * s, e * c, 0.5 * e * c);
  }
};

}  // namespace curvefem::test
