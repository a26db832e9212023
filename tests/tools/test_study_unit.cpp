// Rate fitting of `curvefem study` and the string quoting of `curvefem run --paraview`.
#include <gtest/gtest.h>

#include <cmath>

#include "pipeline/convergence_fit.hpp"
#include "pipeline/paraview_script.hpp"

using namespace curvefem::pipeline;

TEST(ConvergenceFit, RecoversAnExactPowerLaw) {
  // error = 5 · n^(−4/3): rate 4 in h ~ n^(−1/3).
  std::vector<double> n = {100, 800, 6400, 51200}, e;
  for (double x : n) e.push_back(5.0 * std::pow(x, -4.0 / 3.0));
  const auto f = fit_power_law(n, e);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->points, 4);
  EXPECT_NEAR(f->slope, -4.0 / 3.0, 1e-12);
  EXPECT_NEAR(f->rate_h(), 4.0, 1e-12);
  EXPECT_NEAR(std::exp(f->intercept), 5.0, 1e-9);
  for (double r : pairwise_rates_h(n, e)) EXPECT_NEAR(r, 4.0, 1e-12);
}

TEST(ConvergenceFit, IsTheLeastSquaresLineThroughNoisyPoints) {
  // log e = 1, 0, 0 at log n = 0, 1, 2: slope −1/2, intercept 5/6.
  const std::vector<double> n = {1, std::exp(1.0), std::exp(2.0)};
  const std::vector<double> e = {std::exp(1.0), 1, 1};
  const auto f = fit_power_law(n, e);
  ASSERT_TRUE(f);
  EXPECT_NEAR(f->slope, -0.5, 1e-12);
  EXPECT_NEAR(f->intercept, 5.0 / 6.0, 1e-12);
  const auto pairs = pairwise_rates_h(n, e);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_NEAR(pairs[0], 3.0, 1e-12);
  EXPECT_NEAR(pairs[1], 0.0, 1e-12);
}

TEST(ConvergenceFit, SkipsUnusablePointsAndRefusesDegenerateSets) {
  EXPECT_FALSE(fit_power_law({}, {}));
  EXPECT_FALSE(fit_power_law({10}, {1e-3}));
  EXPECT_FALSE(fit_power_law({10, 10, 10}, {1e-3, 2e-3, 3e-3}));  // one n: no slope
  // The same mesh at three degrees (tets constant): the mean of the logs is not exact.
  EXPECT_FALSE(fit_power_law({1865, 1865, 1865}, {3.1e-2, 5.9e-3, 1.8e-3}));
  const auto f = fit_power_law({10, 20, 40, 80}, {1e-2, 0.0, NAN, 1e-2 / 512});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->points, 2);
  EXPECT_NEAR(f->rate_h(), 9.0, 1e-12);  // 512 = 8³ over a factor 8 in n
}

TEST(ParaviewScript, QuotesPathsForPython) {
  EXPECT_EQ(python_string_literal("/tmp/out"), "'/tmp/out'");
  EXPECT_EQ(python_string_literal("it's a\\b"), "'it\\'s a\\\\b'");
  EXPECT_EQ(python_string_literal("a\nb"), "'a\\x0ab'");
  ParaviewScriptOptions o;
  o.dir = "/tmp/it's";
  const std::string s = paraview_state_script(o);
  EXPECT_NE(s.find("HERE = '/tmp/it\\'s'"), std::string::npos) << s;
  EXPECT_NE(s.find("from paraview.simple import *"), std::string::npos);
  EXPECT_EQ(s.back(), '\n');
}
