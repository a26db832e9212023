#include "fem/quadrature/simplex_quadrature.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#include "meshing/core/error.hpp"

namespace curvefem::fem {
namespace generated {
#include "fem/quadrature/generated/symmetric_rules.inc"
}  // namespace generated

namespace {

// Recurrence coefficients of the monic Jacobi polynomials for the weight (1 − t)^alpha on
// [−1, 1] (β = 0): P_{k+1} = (t − a_k) P_k − b_k P_{k−1}.
double jacobi_a(int k, double alpha) {
  if (k == 0) return -alpha / (alpha + 2.0);
  const double s = 2.0 * k + alpha;
  return -alpha * alpha / (s * (s + 2.0));
}

double jacobi_b(int k, double alpha) {  // k ≥ 1
  const double s = 2.0 * k + alpha;
  return 4.0 * k * k * (k + alpha) * (k + alpha) / (s * s * (s + 1.0) * (s - 1.0));
}

// Monic P_n(t) and P_n'(t) by the recurrence.
void monic_jacobi(int n, double alpha, double t, double& value, double& derivative) {
  double p_prev = 0.0, p = 1.0, d_prev = 0.0, d = 0.0;
  for (int k = 0; k < n; ++k) {
    const double b = k == 0 ? 0.0 : jacobi_b(k, alpha);
    const double a = jacobi_a(k, alpha);
    const double p_next = (t - a) * p - b * p_prev;
    const double d_next = p + (t - a) * d - b * d_prev;
    p_prev = p;
    p = p_next;
    d_prev = d;
    d = d_next;
  }
  value = p;
  derivative = d;
}

void check_degree(int degree) {
  if (degree < 0 || degree > k_max_quadrature_degree)
    throw InputError("quadrature degree " + std::to_string(degree) +
                     " is outside the supported range 0.." +
                     std::to_string(k_max_quadrature_degree));
}

int points_per_direction(int degree) { return (degree + 2) / 2; }  // ceil((degree + 1) / 2)

const generated::SymmetricRule* find_symmetric(int dimension, int degree) {
  for (const auto& rule : generated::k_symmetric_rules)
    if (rule.dimension == dimension && rule.degree == degree) return &rule;
  return nullptr;
}

// Every generator expanded to its distinct permutations (std::next_permutation from the sorted
// tuple visits each distinct one once); Cartesian point = barycentric entries 1..dimension.
QuadratureRule expand_symmetric(const generated::SymmetricRule& table) {
  const int dim = table.dimension;
  QuadratureRule rule;
  rule.degree = table.degree;
  rule.points.resize(table.points, dim);
  rule.weights.resize(table.points);
  int q = 0;
  for (int o = 0; o < table.orbit_count; ++o) {
    const generated::SymmetricOrbit& orbit = table.orbits[o];
    std::vector<double> lambda(orbit.barycentric, orbit.barycentric + dim + 1);
    std::sort(lambda.begin(), lambda.end());
    do {
      CF_VERIFY(q < table.points, "generated symmetric rule has more points than declared");
      for (int d = 0; d < dim; ++d) rule.points(q, d) = lambda[d + 1];
      rule.weights[q] = orbit.weight;
      ++q;
    } while (std::next_permutation(lambda.begin(), lambda.end()));
  }
  CF_VERIFY(q == table.points, "generated symmetric rule has fewer points than declared");
  return rule;
}

// The symmetric rule of this degree if the table has one with fewer points than the collapsed
// rule (n^dimension points).
const generated::SymmetricRule* preferred_symmetric(int dimension, int degree) {
  const generated::SymmetricRule* table = find_symmetric(dimension, degree);
  int collapsed = 1;
  for (int d = 0; d < dimension; ++d) collapsed *= points_per_direction(degree);
  return table != nullptr && table->points < collapsed ? table : nullptr;
}

QuadratureRule build_triangle(int degree) {
  if (const auto* table = preferred_symmetric(2, degree)) return expand_symmetric(*table);
  const int n = points_per_direction(degree);
  Eigen::VectorXd u, wu, v, wv;
  gauss_jacobi_01(n, 1, u, wu);
  gauss_jacobi_01(n, 0, v, wv);
  QuadratureRule rule;
  rule.degree = degree;
  rule.points.resize(n * n, 2);
  rule.weights.resize(n * n);
  int q = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j, ++q) {
      rule.points(q, 0) = u[i];
      rule.points(q, 1) = (1.0 - u[i]) * v[j];
      rule.weights[q] = wu[i] * wv[j];
    }
  return rule;
}

QuadratureRule build_tetrahedron(int degree) {
  if (const auto* table = preferred_symmetric(3, degree)) return expand_symmetric(*table);
  const int n = points_per_direction(degree);
  Eigen::VectorXd u, wu, v, wv, w, ww;
  gauss_jacobi_01(n, 2, u, wu);
  gauss_jacobi_01(n, 1, v, wv);
  gauss_jacobi_01(n, 0, w, ww);
  QuadratureRule rule;
  rule.degree = degree;
  rule.points.resize(n * n * n, 3);
  rule.weights.resize(n * n * n);
  int q = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k, ++q) {
        rule.points(q, 0) = u[i];
        rule.points(q, 1) = (1.0 - u[i]) * v[j];
        rule.points(q, 2) = (1.0 - u[i]) * (1.0 - v[j]) * w[k];
        rule.weights[q] = wu[i] * wv[j] * ww[k];
      }
  return rule;
}

// One slot per degree, each filled once; references into the arrays stay valid for the program.
struct RuleCache {
  std::array<std::once_flag, k_max_quadrature_degree + 1> once;
  std::array<QuadratureRule, k_max_quadrature_degree + 1> rules;
};

const QuadratureRule& cached(RuleCache& cache, int degree, QuadratureRule (*build)(int)) {
  check_degree(degree);
  std::call_once(cache.once[degree], [&] { cache.rules[degree] = build(degree); });
  return cache.rules[degree];
}

}  // namespace

void gauss_jacobi_01(int n, int alpha_int, Eigen::VectorXd& nodes, Eigen::VectorXd& weights) {
  CF_VERIFY(n >= 1 && alpha_int >= 0, "Gauss–Jacobi needs n ≥ 1 and alpha ≥ 0");
  const double alpha = alpha_int;
  // Golub–Welsch on [−1, 1]: eigenvalues of the symmetric Jacobi matrix are the nodes.
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < n; ++k) jacobi(k, k) = jacobi_a(k, alpha);
  for (int k = 1; k < n; ++k) jacobi(k, k - 1) = jacobi(k - 1, k) = std::sqrt(jacobi_b(k, alpha));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(jacobi, Eigen::EigenvaluesOnly);
  CF_VERIFY(solver.info() == Eigen::Success, "Golub–Welsch eigenproblem failed");
  Eigen::VectorXd t = solver.eigenvalues();  // increasing

  // Newton polish on the monic recurrence, then Christoffel weights 1 / Σ_k p_k(t)^2 with the
  // orthonormal polynomials p_k: both accurate to round-off for the small n used here.
  const double mu0 = std::pow(2.0, alpha + 1.0) / (alpha + 1.0);  // ∫ (1 − t)^alpha dt
  nodes.resize(n);
  weights.resize(n);
  for (int i = 0; i < n; ++i) {
    double x = t[i];
    for (int it = 0; it < 3; ++it) {
      double value, derivative;
      monic_jacobi(n, alpha, x, value, derivative);
      if (derivative == 0.0) break;
      x -= value / derivative;
    }
    double p_prev = 0.0, p = 1.0 / std::sqrt(mu0), sum = p * p;
    for (int k = 0; k + 1 < n; ++k) {
      const double sb = k == 0 ? 0.0 : std::sqrt(jacobi_b(k, alpha));
      const double p_next =
          ((x - jacobi_a(k, alpha)) * p - sb * p_prev) / std::sqrt(jacobi_b(k + 1, alpha));
      p_prev = p;
      p = p_next;
      sum += p * p;
    }
    // Map t ∈ [−1, 1] to (0, 1): (1 − u)^alpha du = (1 − t)^alpha dt / 2^(alpha + 1).
    nodes[i] = 0.5 * (x + 1.0);
    weights[i] = 1.0 / sum / std::pow(2.0, alpha + 1.0);
  }
}

const QuadratureRule& tetrahedron_quadrature(int degree) {
  static RuleCache cache;
  return cached(cache, degree, &build_tetrahedron);
}

const QuadratureRule& triangle_quadrature(int degree) {
  static RuleCache cache;
  return cached(cache, degree, &build_triangle);
}

int tetrahedron_degree_at_same_cost(int degree) {
  const int points = tetrahedron_quadrature(degree).size();
  while (degree < k_max_quadrature_degree && tetrahedron_quadrature(degree + 1).size() <= points)
    ++degree;
  return degree;
}

int default_quadrature_degree(int p, int k, QuadratureUse use) {
  if (p < 1 || k < 1)
    throw InputError("default_quadrature_degree: basis degree " + std::to_string(p) +
                     " and geometry order " + std::to_string(k) + " must be ≥ 1");
  int degree = 0;
  switch (use) {
    case QuadratureUse::stiffness:
      degree = 2 * p + 2 * (k - 1);
      break;
    case QuadratureUse::mass:
      degree = 2 * p + 3 * (k - 1);
      break;
    case QuadratureUse::error:
      degree = 2 * p + 4 + std::max(2 * k, 3 * (k - 1));
      break;
  }
  return std::min(degree, k_max_quadrature_degree);
}

}  // namespace curvefem::fem
