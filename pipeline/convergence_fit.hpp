// Convergence rates of a study: least-squares fit of log(error) = c + slope · log(n) over the runs
// of one curve, n = DOFs (or tets). With h ~ n^(-1/3) in 3-D the rate with respect to h is
// −3 · slope; an error of O(h^(p+1)) gives slope −(p+1)/3.
#pragma once

#include <optional>
#include <vector>

namespace curvefem::pipeline {

struct PowerLawFit {
  int points = 0;        ///< pairs used (n > 0, error > 0, both finite)
  double slope = 0;      ///< d log(error) / d log(n)
  double intercept = 0;  ///< log(error) at n = 1
  double rate_h() const { return -3.0 * slope; }
};

/// Fits error ≈ exp(intercept) · n^slope to the pairs (n[i], error[i]); pairs that are not
/// positive and finite are skipped. nullopt with fewer than two usable pairs or when every usable
/// n is the same.
std::optional<PowerLawFit> fit_power_law(const std::vector<double>& n,
                                         const std::vector<double>& error);

/// −3 · slope between consecutive pairs (sorted by n as given; skipped pairs leave no entry).
std::vector<double> pairwise_rates_h(const std::vector<double>& n,
                                     const std::vector<double>& error);

}  // namespace curvefem::pipeline
