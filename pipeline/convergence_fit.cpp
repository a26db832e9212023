#include "pipeline/convergence_fit.hpp"

#include <cmath>

namespace curvefem::pipeline {
namespace {
bool usable(double n, double e) { return std::isfinite(n) && std::isfinite(e) && n > 0 && e > 0; }
}  // namespace

std::optional<PowerLawFit> fit_power_law(const std::vector<double>& n,
                                         const std::vector<double>& error) {
  std::vector<double> x, y;
  bool distinct = false;  // compared exactly: rounding in the sums below must not make a slope
  for (std::size_t i = 0; i < n.size() && i < error.size(); ++i)
    if (usable(n[i], error[i])) {
      x.push_back(std::log(n[i]));
      y.push_back(std::log(error[i]));
      distinct = distinct || x.back() != x.front();
    }
  if (x.size() < 2 || !distinct) return std::nullopt;
  const double m = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) mx += x[i] / m, my += y[i] / m;
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  if (!(sxx > 1e-300)) return std::nullopt;
  PowerLawFit f;
  f.points = static_cast<int>(x.size());
  f.slope = sxy / sxx;
  f.intercept = my - f.slope * mx;
  return f;
}

std::vector<double> pairwise_rates_h(const std::vector<double>& n,
                                     const std::vector<double>& error) {
  std::vector<double> rates;
  int previous = -1;
  for (std::size_t i = 0; i < n.size() && i < error.size(); ++i) {
    if (!usable(n[i], error[i])) continue;
    if (previous >= 0 && n[i] != n[previous])
      rates.push_back(-3.0 * std::log(error[i] / error[previous]) / std::log(n[i] / n[previous]));
    previous = static_cast<int>(i);
  }
  return rates;
}

}  // namespace curvefem::pipeline
