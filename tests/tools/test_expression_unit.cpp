// Case expressions: the forward-mode differentiation (pipeline/expression_ad.hpp) against
// muparser's values and 4th-order central differences, over every operator and function of the
// grammar, and its fallback where the check at the fixed points fails.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "meshing/core/error.hpp"
#include "pipeline/expression.hpp"
#include "pipeline/expression_ad.hpp"

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

// Every operator and function of the grammar.
const char* const kTexts[] = {
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

}  // namespace

TEST(Expression, ForwardModeGradientsMatchFiniteDifferencesForEveryOperatorAndFunction) {
  for (const char* text : kTexts) {
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

TEST(Expression, TheBatchedEvaluationEqualsThePointwiseOneForEveryOperatorAndFunction) {
  // 150 points: two full blocks of 64 and a partial one. Each text is also evaluated with
  // values only (no gradient arrays), and the one on finite differences goes point by point.
  const std::vector<Eigen::Vector3d> points = sample_points(150);
  const int n = static_cast<int>(points.size());
  std::vector<double> x(n), y(n), z(n);
  for (int i = 0; i < n; ++i) x[i] = points[i][0], y[i] = points[i][1], z[i] = points[i][2];
  std::vector<const char*> texts(std::begin(kTexts), std::end(kTexts));
  texts.push_back("abs(x - 0.1)");
  for (const char* text : texts) {
    SCOPED_TRACE(text);
    const Expression e(text, "/test");
    std::vector<double> v(n), gx(n), gy(n), gz(n), w(n, -1.0);
    e.values_and_gradients(n, x.data(), y.data(), z.data(), v.data(), gx.data(), gy.data(),
                           gz.data());
    e.values_and_gradients(n, x.data(), y.data(), z.data(), w.data(), nullptr, nullptr, nullptr);
    for (int i = 0; i < n; ++i) {
      Eigen::Vector3d g;
      const double vi = e.value_and_gradient(points[i], &g);
      const double tol = 1e-14 * std::max(1.0, std::fabs(vi));
      ASSERT_NEAR(v[i], vi, tol) << "point " << i;
      ASSERT_EQ(w[i], v[i]) << "point " << i;
      const Eigen::Vector3d gb(gx[i], gy[i], gz[i]);
      ASSERT_LE((gb - g).norm(), 1e-14 * std::max(1.0, g.norm())) << "point " << i;
    }
  }
}

TEST(Expression, TheBatchedSinAndCosAreWithinTwoUlpOfGlibc) {
  std::mt19937_64 rng(11);
  std::vector<double> x;
  for (const double range : {1.0, 10.0, 1e3, 1e5}) {
    std::uniform_real_distribution<double> d(-range, range);
    for (int i = 0; i < 100000; ++i) x.push_back(d(rng));
  }
  // Next to the multiples of π/2, where the reduction cancels, up to |x| = 1e5.
  for (int k = -63000; k <= 63000; k += 7) {
    const double v = k * (M_PI / 2);
    x.insert(x.end(), {v, std::nextafter(v, 1e9), std::nextafter(v, -1e9)});
  }
  // The fallback: beyond 1e5, infinities and NaN.
  const std::size_t fallback = x.size();
  x.insert(x.end(), {1e5 + 0.5, -3e7, 1e300, INFINITY, -INFINITY, NAN});
  const int n = static_cast<int>(x.size());
  std::vector<double> s(n), c(n);
  curvefem::pipeline::sincos_batch(n, x.data(), s.data(), c.data());
  auto ulp = [](double v) {
    v = std::fabs(v);
    return std::nextafter(v, INFINITY) - v;
  };
  double worst_sin = 0, worst_cos = 0;
  for (int i = 0; i < n; ++i) {
    double rs, rc;
    ::sincos(x[i], &rs, &rc);
    if (std::size_t(i) >= fallback) {
      EXPECT_TRUE(std::isnan(rs) ? std::isnan(s[i]) : s[i] == rs) << x[i];
      EXPECT_TRUE(std::isnan(rc) ? std::isnan(c[i]) : c[i] == rc) << x[i];
      continue;
    }
    worst_sin = std::max(worst_sin, std::fabs(s[i] - rs) / ulp(rs));
    worst_cos = std::max(worst_cos, std::fabs(c[i] - rc) / ulp(rc));
  }
  EXPECT_LE(worst_sin, 2.0);
  EXPECT_LE(worst_cos, 2.0);
  // Either output may be left out.
  std::vector<double> only(n);
  curvefem::pipeline::sincos_batch(n, x.data(), nullptr, only.data());
  for (int i = 0; i < n; ++i) ASSERT_TRUE(only[i] == c[i] || std::isnan(c[i]));
}

TEST(Expression, AConstantIsRecognizedOnlyWithoutVariables) {
  // Expression::constant() lets the pipeline pass a constant κ as a number (fem's reference-
  // tensor kernel on straight cells); any use of x, y, z, t or the normal is not constant.
  ASSERT_TRUE(Expression("1", "/k").constant().has_value());
  EXPECT_EQ(*Expression("1", "/k").constant(), 1.0);
  ASSERT_TRUE(Expression("2*pi + sin(0.5)^2", "/k").constant().has_value());
  EXPECT_DOUBLE_EQ(*Expression("2*pi + sin(0.5)^2", "/k").constant(),
                   2 * M_PI + std::sin(0.5) * std::sin(0.5));
  for (const char* text : {"x", "1 + 0*y", "z^0", "t", "2*nx"})
    EXPECT_FALSE(Expression(text, "/k", true).constant().has_value()) << text;
}
