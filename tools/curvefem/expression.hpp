// Scalar expressions of x, y, z, t from case files (muparser). Compiled once at construction,
// so a syntax error or an unknown variable is an InputError naming the JSON path of the key;
// evaluation is thread-safe (one parser per thread) and allocation-free after the first call.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

namespace curvefem::cli {

class Expression {
 public:
  Expression() = default;
  /// `where`: JSON path used in error messages, e.g. "/boundary_conditions/0/value".
  Expression(std::string text, std::string where);
  double operator()(const Eigen::Vector3d& x, double t = 0.0) const;
  /// ∇ by a 4th-order central difference with step h (error ~ h⁴·|∂⁵u| + 1e-16/h).
  Eigen::Vector3d gradient(const Eigen::Vector3d& x, double h = 1e-3) const;
  const std::string& text() const { return m_text; }
  bool empty() const { return m_text.empty(); }

 private:
  std::string m_text;
  long long m_id = -1;
};

}  // namespace curvefem::cli
