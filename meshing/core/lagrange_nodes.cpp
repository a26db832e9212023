#include "meshing/core/lagrange_nodes.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

#include "meshing/core/error.hpp"

namespace curvefem {
namespace {

std::vector<std::array<int, 4>> build_lattice(int dim, int k) {
  std::vector<std::array<int, 4>> nodes;
  for (int a1 = 0; a1 <= k; ++a1)
    for (int a2 = 0; a1 + a2 <= k; ++a2)
      for (int a3 = 0; a1 + a2 + a3 <= k; ++a3) {
        if (dim == 2 && a3 > 0) continue;
        nodes.push_back({k - a1 - a2 - a3, a1, a2, a3});
      }
  auto entity = [dim](const std::array<int, 4>& a) {
    std::vector<int> e;
    for (int i = 0; i <= dim; ++i)
      if (a[i] > 0) e.push_back(i);
    return e;
  };
  std::sort(nodes.begin(), nodes.end(), [&](const auto& x, const auto& y) {
    const auto ex = entity(x), ey = entity(y);
    if (ex.size() != ey.size()) return ex.size() < ey.size();
    if (ex != ey) return ex < ey;
    return x > y;  // descending lexicographic
  });
  return nodes;
}

// d/dλ of Π_{j<a} (kλ - j)/(j+1), and its value.
void factor(int a, int k, double lambda, double& value, double& derivative) {
  value = 1.0;
  derivative = 0.0;
  for (int j = 0; j < a; ++j) {
    const double f = (k * lambda - j) / (j + 1.0);
    const double df = k / (j + 1.0);
    derivative = derivative * f + value * df;
    value *= f;
  }
}

void check_order(int order) {
  if (order < 1 || order > 10)
    throw InputError("Lagrange order " + std::to_string(order) +
                     " is outside the supported range 1..10");
}

}  // namespace

int cell_dimension(CellKind kind) { return kind == CellKind::triangle ? 2 : 3; }

int num_lagrange_nodes(CellKind kind, int k) {
  return kind == CellKind::triangle ? (k + 1) * (k + 2) / 2 : (k + 1) * (k + 2) * (k + 3) / 6;
}

int order_from_node_count(CellKind kind, int n) {
  for (int k = 1; k <= 10; ++k)
    if (num_lagrange_nodes(kind, k) == n) return k;
  return -1;
}

const std::vector<std::array<int, 4>>& lagrange_lattice(CellKind kind, int order) {
  check_order(order);
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::vector<std::array<int, 4>>> cache;
  std::lock_guard lock(mutex);
  const int dim = cell_dimension(kind);
  auto [it, inserted] = cache.try_emplace({dim, order});
  if (inserted) it->second = build_lattice(dim, order);
  return it->second;
}

Eigen::MatrixXd lagrange_reference_nodes(CellKind kind, int order) {
  const auto& lattice = lagrange_lattice(kind, order);
  const int dim = cell_dimension(kind);
  Eigen::MatrixXd x(lattice.size(), dim);
  for (std::size_t i = 0; i < lattice.size(); ++i)
    for (int d = 0; d < dim; ++d) x(i, d) = static_cast<double>(lattice[i][d + 1]) / order;
  return x;
}

Eigen::VectorXd lagrange_shape_values(CellKind kind, int order, const Eigen::Vector3d& xi) {
  const auto& lattice = lagrange_lattice(kind, order);
  const int dim = cell_dimension(kind);
  double lambda[4] = {1.0, xi[0], xi[1], dim == 3 ? xi[2] : 0.0};
  lambda[0] = 1.0 - lambda[1] - lambda[2] - lambda[3];
  Eigen::VectorXd phi(lattice.size());
  for (std::size_t n = 0; n < lattice.size(); ++n) {
    double v = 1.0;
    for (int i = 0; i <= dim; ++i) {
      double f, df;
      factor(lattice[n][i], order, lambda[i], f, df);
      v *= f;
    }
    phi[n] = v;
  }
  return phi;
}

Eigen::MatrixXd lagrange_shape_gradients(CellKind kind, int order, const Eigen::Vector3d& xi) {
  const auto& lattice = lagrange_lattice(kind, order);
  const int dim = cell_dimension(kind);
  double lambda[4] = {1.0, xi[0], xi[1], dim == 3 ? xi[2] : 0.0};
  lambda[0] = 1.0 - lambda[1] - lambda[2] - lambda[3];
  Eigen::MatrixXd grad(lattice.size(), dim);
  for (std::size_t n = 0; n < lattice.size(); ++n) {
    double f[4], df[4];
    for (int i = 0; i <= dim; ++i) factor(lattice[n][i], order, lambda[i], f[i], df[i]);
    double dlambda[4];  // ∂φ/∂λ_i
    for (int i = 0; i <= dim; ++i) {
      double p = df[i];
      for (int j = 0; j <= dim; ++j)
        if (j != i) p *= f[j];
      dlambda[i] = p;
    }
    for (int d = 0; d < dim; ++d) grad(n, d) = dlambda[d + 1] - dlambda[0];
  }
  return grad;
}

double triangle_area_element_ratio(int order, const std::vector<Eigen::Vector3d>& nodes) {
  // Shape gradients at the samples, per order (built once, read-only after).
  static const std::array<std::vector<Eigen::MatrixXd>, k_max_order + 1> gradients = [] {
    std::array<std::vector<Eigen::MatrixXd>, k_max_order + 1> out;
    for (int k = 1; k <= k_max_order; ++k)
      for (int j = 0, m = 4 * k; j <= m; ++j)
        for (int i = 0; i + j <= m; ++i)
          out[std::size_t(k)].push_back(lagrange_shape_gradients(
              CellKind::triangle, k, Eigen::Vector3d(double(i) / m, double(j) / m, 0)));
    return out;
  }();
  const auto& lattice = lagrange_lattice(CellKind::triangle, order);
  Eigen::Vector3d corner[3] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                               Eigen::Vector3d::Zero()};  // every lattice has its three corners
  for (std::size_t n = 0; n < lattice.size(); ++n)
    for (int c = 0; c < 3; ++c)
      if (lattice[n][std::size_t(c)] == order) corner[c] = nodes[n];
  const Eigen::Vector3d n0 = (corner[1] - corner[0]).cross(corner[2] - corner[0]);
  double lo = HUGE_VAL, hi = 0;
  for (const Eigen::MatrixXd& g : gradients[std::size_t(order)]) {
    Eigen::Vector3d xu = Eigen::Vector3d::Zero(), xv = Eigen::Vector3d::Zero();
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      xu += g(Eigen::Index(n), 0) * nodes[n];
      xv += g(Eigen::Index(n), 1) * nodes[n];
    }
    const Eigen::Vector3d c = xu.cross(xv);
    const double a = c.dot(n0) > 0 ? c.norm() : 0.0;
    lo = std::min(lo, a);
    hi = std::max(hi, a);
  }
  return hi > 0 ? lo / hi : 0.0;
}

}  // namespace curvefem
