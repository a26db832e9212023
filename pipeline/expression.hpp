// Scalar expressions of x, y, z, t from case files (muparser). Compiled once at construction,
// so a syntax error or an unknown variable is an InputError naming the JSON path of the key;
// evaluation is thread-safe (one parser per thread) and allocation-free after the first call.
// Neumann values may also use nx, ny, nz: the mesh's outward unit normal at the quadrature point
// (cases/README.md).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

namespace curvefem::pipeline {

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
  /// ∇ by a 4th-order central difference with step h (error ~ h⁴·|∂⁵u| + 1e-16/h).
  Eigen::Vector3d gradient(const Eigen::Vector3d& x, double h = 1e-3) const;
  const std::string& text() const { return m_text; }
  bool empty() const { return m_text.empty(); }

 private:
  std::string m_text;
  long long m_id = -1;
  bool m_uses_normal = false;
};

}  // namespace curvefem::pipeline
