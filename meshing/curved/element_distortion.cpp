#include "meshing/curved/element_distortion.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"

namespace curvefem::meshing::curved {

namespace {

// ∂^e x^n (one variable): n (n-1) .. (n-e+1) x^(n-e).
double derivative_1d(int n, int e, double x) {
  if (e > n) return 0;
  double c = 1;
  for (int i = 0; i < e; ++i) c *= n - i;
  return c * std::pow(x, n - e);
}

// Per order: the basis in monomial form and the derivative tables of the monomials at the
// sample points. F(ξ) = Σ_m A_m ξ^{e_m} with A = C X.
struct Tables {
  Eigen::MatrixXd C;  // n × n: row m = coefficients of monomial m in each basis function
  // Per sample: first (3 rows), second (6: xx yy zz xy xz yz), third (10) derivatives of every
  // monomial; weights: the multiplicity of each entry in the Frobenius norm of the full tensor.
  std::vector<Eigen::MatrixXd> d1, d2, d3;
};

const std::array<std::array<int, 3>, 6> k_second = {
    {{2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1}}};
const double k_second_weight[6] = {1, 1, 1, 2, 2, 2};
const std::array<std::array<int, 3>, 10> k_third = {{{3, 0, 0},
                                                     {0, 3, 0},
                                                     {0, 0, 3},
                                                     {2, 1, 0},
                                                     {2, 0, 1},
                                                     {1, 2, 0},
                                                     {0, 2, 1},
                                                     {1, 0, 2},
                                                     {0, 1, 2},
                                                     {1, 1, 1}}};
const double k_third_weight[10] = {1, 1, 1, 3, 3, 3, 3, 3, 3, 6};

Tables build_tables(int k) {
  std::vector<std::array<int, 3>> mono;
  for (int a = 0; a <= k; ++a)
    for (int b = 0; a + b <= k; ++b)
      for (int c = 0; a + b + c <= k; ++c) mono.push_back({a, b, c});
  const Eigen::MatrixXd ref = lagrange_reference_nodes(CellKind::tetrahedron, k);
  const int n = int(ref.rows());
  CF_VERIFY(int(mono.size()) == n, "element_distortion: monomial count");
  Eigen::MatrixXd V(n, n);
  for (int j = 0; j < n; ++j)
    for (int m = 0; m < n; ++m)
      V(j, m) = std::pow(ref(j, 0), mono[m][0]) * std::pow(ref(j, 1), mono[m][1]) *
                std::pow(ref(j, 2), mono[m][2]);
  Tables t;
  t.C = V.fullPivLu().inverse();
  const int ks = std::max(k, 2);
  Eigen::MatrixXd samples = lagrange_reference_nodes(CellKind::tetrahedron, ks);
  samples.conservativeResize(samples.rows() + 1, 3);
  samples.row(samples.rows() - 1) = Eigen::RowVector3d(0.25, 0.25, 0.25);
  auto table = [&](const Eigen::RowVector3d& x, const auto& orders) {
    Eigen::MatrixXd out(Eigen::Index(orders.size()), n);
    for (std::size_t r = 0; r < orders.size(); ++r)
      for (int m = 0; m < n; ++m) {
        double v = 1;
        for (int d = 0; d < 3; ++d) v *= derivative_1d(mono[m][d], orders[r][d], x[d]);
        out(Eigen::Index(r), m) = v;
      }
    return out;
  };
  const std::array<std::array<int, 3>, 3> first = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (Eigen::Index s = 0; s < samples.rows(); ++s) {
    const Eigen::RowVector3d x = samples.row(s);
    t.d1.push_back(table(x, first));
    t.d2.push_back(table(x, k_second));
    t.d3.push_back(table(x, k_third));
  }
  return t;
}

const Tables& tables(int k) {
  static std::array<std::once_flag, 5> once;
  static std::array<Tables, 5> all;
  std::call_once(once[std::size_t(k)], [k] { all[std::size_t(k)] = build_tables(k); });
  return all[std::size_t(k)];
}

}  // namespace

ElementDistortion element_distortion(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes) {
  if (order < 1 || order > 4)
    throw InputError("element_distortion: order " + std::to_string(order) + " is not in 1..4");
  if (nodes.rows() != num_lagrange_nodes(CellKind::tetrahedron, order) || nodes.cols() != 3)
    throw InputError("element_distortion: " + std::to_string(nodes.rows()) + " × " +
                     std::to_string(nodes.cols()) + " nodes for an order-" + std::to_string(order) +
                     " tet");
  const Tables& t = tables(order);
  const Eigen::MatrixXd A = t.C * nodes;  // monomial coefficients, n × 3
  ElementDistortion out;
  double min_det = HUGE_VAL, max_det = -HUGE_VAL;
  for (std::size_t s = 0; s < t.d1.size(); ++s) {
    const Eigen::Matrix3d J = (t.d1[s] * A).transpose();  // J(c, a) = ∂F_c / ∂ξ_a
    const double det = J.determinant();
    min_det = std::min(min_det, det);
    max_det = std::max(max_det, det);
    const Eigen::MatrixXd H2 = t.d2[s] * A, H3 = t.d3[s] * A;
    double n2 = 0, n3 = 0;
    for (int r = 0; r < 6; ++r) n2 += k_second_weight[r] * H2.row(r).squaredNorm();
    for (int r = 0; r < 10; ++r) n3 += k_third_weight[r] * H3.row(r).squaredNorm();
    const double sigma_min = Eigen::JacobiSVD<Eigen::Matrix3d>(J).singularValues()[2];
    auto relative = [&](double n) {
      const double v = std::sqrt(n);
      return v == 0 ? 0.0 : sigma_min > 0 ? v / sigma_min : HUGE_VAL;
    };
    out.d2 = std::max(out.d2, relative(n2));
    out.d3 = std::max(out.d3, relative(n3));
  }
  out.jacobian_ratio = max_det > 0 ? min_det / max_det : -1.0;
  return out;
}

}  // namespace curvefem::meshing::curved
