// Case expressions: the forward-mode differentiation (pipeline/expression_ad.hpp) against
// muparser's values and 4th-order central differences, over every operator and function of the
// grammar, and its fallback where the check at the fixed points fails.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "meshing/core/error.hpp"
#include "pipeline/expression.hpp"

using curvefem::pipeline::Expression;

namespace {

// Points in a box where every expression below is smooth and defined.
std::vector<Eigen::Vector3d> sample_points(int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(-0.9, 0.9);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < n; ++i) out.emplace_back(d(rng), d(rng), d(rng));
  return out;
}

}  // namespace

TEST(Expression, ForwardModeGradientsMatchFiniteDifferencesForEveryOperatorAndFunction) {
  const char* texts[] = {
      "cos(pi*x)*cos(pi*y)*cos(pi*z)",
      "-x^2 + 2^-y - z^3",
      "2^x^2",  // muparser: right-associative, 2^(x^2)
      "x/(2 + y*y) - (z - 1)/(x + 3)",
      "exp(x/2)*sin(y + z/2)",
      "tan(x/2) + asin(y/2) + acos(z/3) + atan(x*y)",
      "sinh(x) + cosh(y) + tanh(z) + asinh(x*y) + acosh(2 + z*z) + atanh(y/2)",
      "log2(3 + x) + log10(3 + y) + log(3 + z) + ln(2 + x*y)",
      "sqrt(2 + x*y*z) + abs(x - 2) + sign(y - 5) + rint(0.2*z)",
      "x < 0.95 ? x*y : -z",
      "x > -1 && y < 1 ? z^2 : 0",
      "x > 5 || y < -5 ? 0 : x*z",
      "x <= 1 ? (y >= -1 ? 1 : 0) * x : 0",
      "(x == 7) + (y != 7) * y",
      "min(x + 2, y + 3, 10) + max(z - 5, -x - 4)",
      "sum(x, y, z*z) + avg(x, 2*y, 3*z)",
      "atan2(y + 2, x + 3) + _pi*_e*z",
      "1e-3*x + .5*y + 5.*z + 2E2",
      "(1 + x)^(1 + y)",
  };
  for (const char* text : texts) {
    SCOPED_TRACE(text);
    const Expression e(text, "/test");
    EXPECT_TRUE(e.differentiated());
    for (const Eigen::Vector3d& x : sample_points(20)) {
      Eigen::Vector3d g;
      const double v = e.value_and_gradient(x, &g);
      const double mu = e(x);
      EXPECT_NEAR(v, mu, 1e-13 * std::max(1.0, std::fabs(mu)));
      const Eigen::Vector3d fd = e.difference_gradient(x);
      EXPECT_LE((g - fd).norm(), 1e-8 * std::max(1.0, fd.norm()))
          << g.transpose() << " vs " << fd.transpose();
      EXPECT_EQ(e.gradient(x), g);
    }
  }
}

TEST(Expression, TextTheDifferentiationCannotCheckStaysOnFiniteDifferences) {
  // A kink at the first check point (x = 0.1): the central difference there is 0, the forward
  // mode 1, so the check fails and gradient() is the difference.
  const Expression kink("abs(x - 0.1)", "/test");
  EXPECT_FALSE(kink.differentiated());
  const Eigen::Vector3d x(0.5, 0, 0);
  EXPECT_EQ(kink.gradient(x), kink.difference_gradient(x));
  EXPECT_NEAR(kink.gradient(x)[0], 1.0, 1e-9);
  // Syntax muparser has and this grammar has not (assignment): finite differences too.
  const Expression assign("y = x*2", "/test");
  EXPECT_FALSE(assign.differentiated());
  EXPECT_NEAR(assign.gradient(x)[0], 2.0, 1e-9);
  // Errors are still muparser's.
  EXPECT_THROW(Expression("cos(", "/test"), curvefem::InputError);
}
