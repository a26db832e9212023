// Scalar expressions of x, y, z, t from case files (muparser). Compiled once at construction,
// so a syntax error or an unknown variable is an InputError naming the JSON path of the key;
// evaluation is thread-safe (one parser per thread) and allocation-free after the first call.
// Neumann values may also use nx, ny, nz: the mesh's outward unit normal at the quadrature point
// (cases/README.md).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>

namespace curvefem::pipeline {

class DualExpression;

class Expression {
 public:
  Expression() = default;
  /// `where`: JSON path used in error messages, e.g. "/boundary_conditions/0/value".
  /// `normal_allowed`: whether nx, ny, nz may appear (boundary-condition values; the case file
  /// then refuses them in Dirichlet values); elsewhere they are an InputError.
  Expression(std::string text, std::string where, bool normal_allowed = false);
  double operator()(const Eigen::Vector3d& x, double t = 0.0) const;
  /// With the normal n bound to nx, ny, nz (the one-argument form binds n = 0).
  double operator()(const Eigen::Vector3d& x, const Eigen::Vector3d& n, double t = 0.0) const;
  /// Whether the text uses nx, ny or nz.
  bool uses_normal() const { return m_uses_normal; }
  /// ∇u at x: by forward-mode differentiation of the text where `differentiated()` (exact up to
  /// rounding, about the cost of one evaluation; expression_ad.hpp), else by a 4th-order central
  /// difference with step h (twelve evaluations; error ~ h⁴·|∂⁵u| + 1e-16/h).
  Eigen::Vector3d gradient(const Eigen::Vector3d& x, double h = 1e-3) const;
  /// u(x) and ∇u(x) in one evaluation where differentiated(), else the two separately.
  double value_and_gradient(const Eigen::Vector3d& x, Eigen::Vector3d* gradient) const;
  /// u and, where gx is not null, ∇u at `count` points (structure of arrays): one pass of the
  /// batched evaluator of expression_ad.hpp over the points where differentiated(), else point
  /// by point as value_and_gradient(). t = 0, n = 0.
  void values_and_gradients(int count, const double* x, const double* y, const double* z,
                            double* value, double* gx, double* gy, double* gz) const;
  /// The same by the finite difference always (what the differentiation is checked against).
  Eigen::Vector3d difference_gradient(const Eigen::Vector3d& x, double h = 1e-3) const;
  /// The same with the normal bound to nx, ny, nz and time t.
  Eigen::Vector3d difference_gradient(const Eigen::Vector3d& x, const Eigen::Vector3d& n, double t,
                                      double h = 1e-3) const;
  /// Whether gradient() differentiates: the text parsed in the grammar of expression_ad.hpp and
  /// its values matched muparser's (relative 1e-12) and its gradient the finite difference
  /// (relative 1e-6) at 6 fixed points (t = 0.37, a fixed unit normal).
  bool differentiated() const { return m_dual != nullptr; }
  const std::string& text() const { return m_text; }
  /// The value, when the text uses none of x, y, z, t, nx, ny, nz (e.g. "1", "2*pi").
  std::optional<double> constant() const { return m_constant; }
  bool empty() const { return m_text.empty(); }

 private:
  std::string m_text;
  long long m_id = -1;
  bool m_uses_normal = false;
  std::optional<double> m_constant;
  std::shared_ptr<const DualExpression> m_dual;
};

}  // namespace curvefem::pipeline
