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

namespace curvefem::pipeline {

class DualExpression {
 public:
  /// nullptr when the text uses syntax outside the grammar above (the caller falls back).
  static std::unique_ptr<const DualExpression> compile(const std::string& text);
  ~DualExpression();

  /// u(x) and ∇u(x); t and the normal n are parameters (no derivative).
  double evaluate(const Eigen::Vector3d& x, const Eigen::Vector3d& n, double t,
                  Eigen::Vector3d* gradient) const;

  struct Node;

 private:
  DualExpression();
  std::unique_ptr<Node[]> m_nodes;
  int m_size = 0, m_root = -1;
};

}  // namespace curvefem::pipeline
