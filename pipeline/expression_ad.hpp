// Forward-mode differentiation of case expressions (issue 24, "expressions at speed"): the text is
// parsed a second time, independently of muparser, into a tree of muparser's default grammar
// (numbers, x y z t nx ny nz pi and muparser's constants, + - * / ^, unary ±, comparisons, && ||,
// ?:, and its built-in functions, atan2 and min/max/sum/avg included), and evaluated with dual
// numbers: the value and ∂/∂x, ∂/∂y, ∂/∂z in one pass, each transcendental function evaluated once.
// Against the 4th-order central difference of Expression::gradient (twelve evaluations), this is
// exact up to rounding and costs about one.
//
// The tree is used only where it is checked: Expression compiles it and compares its values with
// muparser's and its gradient with the finite difference at fixed points; text this grammar does
// not cover, or any disagreement, leaves the expression on finite differences.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace curvefem::pipeline {

/// sin and cos of x[i] for i < count (either output may be null), as the batched evaluation's
/// sin and cos nodes compute them: a branch-free kernel the compiler can vectorize for
/// |x| <= 1e5 (Cody–Waite reduction by π/2 in three parts of 33, 33 and 53 bits, then the Taylor
/// series of sin and cos on [−π/4, π/4] to the 17th and 18th powers, whose truncation is below
/// 1e-19), glibc's sincos elsewhere (and for non-finite x). Within 2 ulp of glibc's values
/// (measured on 4.4M points up to |x| = 1e5: 1 in 3,000 above 1 ulp, none above 2; the test in
/// tests/tools/test_expression_unit.cpp), about 3x faster than glibc's sincos with SSE2.
void sincos_batch(int count, const double* x, double* sin_out, double* cos_out);

class DualExpression {
 public:
  /// nullptr when the text uses syntax outside the grammar above (the caller falls back).
  static std::unique_ptr<const DualExpression> compile(const std::string& text);
  ~DualExpression();

  /// u(x) and ∇u(x); t and the normal n are parameters (no derivative).
  double evaluate(const Eigen::Vector3d& x, const Eigen::Vector3d& n, double t,
                  Eigen::Vector3d* gradient) const;

  /// The same at `count` points at once (structure of arrays, each of length count): value[i]
  /// and, where gx is not null, the gradient (gx, gy, gz)[i] at (x, y, z)[i]. The normal arrays
  /// may be null (n = 0). The tree is walked once per block of points rather than once per
  /// point, every operation a loop over the block; a ternary evaluates both branches and
  /// selects per point. The same operations in the same order as evaluate(), except sin and cos
  /// (sincos_batch): equal to a few ulp (checked at construction by Expression, and by a test).
  void evaluate(int count, const double* x, const double* y, const double* z, const double* nx,
                const double* ny, const double* nz, double t, double* value, double* gx, double* gy,
                double* gz) const;

  struct Node;

 private:
  DualExpression();
  std::unique_ptr<Node[]> m_nodes;
  int m_size = 0, m_root = -1;
  std::vector<int> m_order;  ///< the nodes reachable from the root, children first
};

}  // namespace curvefem::pipeline
