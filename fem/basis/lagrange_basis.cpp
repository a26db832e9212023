#include "fem/basis/lagrange_basis.hpp"

#include <string>

#include "meshing/core/error.hpp"

namespace curvefem::fem {
namespace generated {
#include "fem/basis/generated/lagrange_tables.inc"
}  // namespace generated

namespace {

constexpr int k_max_basis_degree = 4;
constexpr int k_max_basis_size = 35;  // tetrahedron, p = 4

// Powers x^0..x^p of each coordinate, then the monomials and their partial derivatives.
struct Monomials {
  double value[k_max_basis_size];
  double derivative[3][k_max_basis_size];
};

void powers(const double* xi, int dim, int p, double pw[3][k_max_basis_degree + 1]) {
  for (int d = 0; d < 3; ++d) {
    pw[d][0] = 1.0;
    const double x = d < dim ? xi[d] : 0.0;
    for (int e = 1; e <= p; ++e) pw[d][e] = pw[d][e - 1] * x;
  }
}

}  // namespace

LagrangeBasis::LagrangeBasis(CellKind kind, int degree)
    : m_kind(kind), m_degree(degree), m_dim(cell_dimension(kind)) {
  if (degree < 1 || degree > k_max_basis_degree)
    throw InputError("Lagrange basis degree " + std::to_string(degree) +
                     " is outside the supported range 1..4");
  const generated::LagrangeTable* found = nullptr;
  for (const auto& table : generated::k_lagrange_tables)
    if (table.dimension == m_dim && table.degree == degree) found = &table;
  CF_VERIFY(found != nullptr, "no generated Lagrange table for this kind and degree");
  m_size = found->size;
  m_lattice = found->lattice;
  m_exponents = found->exponents;
  m_coefficients = found->coefficients;
  CF_VERIFY(m_size == num_lagrange_nodes(kind, degree), "generated table has a wrong size");
}

void LagrangeBasis::values(const double* xi, double* phi) const {
  double pw[3][k_max_basis_degree + 1];
  powers(xi, m_dim, m_degree, pw);
  double mono[k_max_basis_size];
  for (int m = 0; m < m_size; ++m) {
    const int* e = m_exponents + 3 * m;
    mono[m] = pw[0][e[0]] * pw[1][e[1]] * pw[2][e[2]];
  }
  for (int i = 0; i < m_size; ++i) {
    const double* c = m_coefficients + i * m_size;
    double v = 0.0;
    for (int m = 0; m < m_size; ++m) v += c[m] * mono[m];
    phi[i] = v;
  }
}

void LagrangeBasis::gradients(const double* xi, double* grad) const {
  values_and_gradients(xi, nullptr, grad);
}

void LagrangeBasis::values_and_gradients(const double* xi, double* phi, double* grad) const {
  double pw[3][k_max_basis_degree + 1];
  powers(xi, m_dim, m_degree, pw);
  Monomials mono;
  for (int m = 0; m < m_size; ++m) {
    const int* e = m_exponents + 3 * m;
    const double px = pw[0][e[0]], py = pw[1][e[1]], pz = pw[2][e[2]];
    mono.value[m] = px * py * pz;
    mono.derivative[0][m] = e[0] > 0 ? e[0] * pw[0][e[0] - 1] * py * pz : 0.0;
    mono.derivative[1][m] = e[1] > 0 ? e[1] * px * pw[1][e[1] - 1] * pz : 0.0;
    mono.derivative[2][m] = e[2] > 0 ? e[2] * px * py * pw[2][e[2] - 1] : 0.0;
  }
  for (int i = 0; i < m_size; ++i) {
    const double* c = m_coefficients + i * m_size;
    double v = 0.0, g[3] = {0.0, 0.0, 0.0};
    for (int m = 0; m < m_size; ++m) {
      v += c[m] * mono.value[m];
      for (int d = 0; d < m_dim; ++d) g[d] += c[m] * mono.derivative[d][m];
    }
    if (phi) phi[i] = v;
    for (int d = 0; d < m_dim; ++d) grad[d * m_size + i] = g[d];
  }
}

Eigen::VectorXd LagrangeBasis::values(const Eigen::Vector3d& xi) const {
  Eigen::VectorXd phi(m_size);
  values(xi.data(), phi.data());
  return phi;
}

Eigen::MatrixXd LagrangeBasis::gradients(const Eigen::Vector3d& xi) const {
  Eigen::MatrixXd grad(m_size, m_dim);
  gradients(xi.data(), grad.data());
  return grad;
}

BasisTabulation LagrangeBasis::tabulate(const QuadratureRule& rule) const {
  if (rule.dimension() != m_dim)
    throw InputError("quadrature rule of dimension " + std::to_string(rule.dimension()) +
                     " used with a basis of dimension " + std::to_string(m_dim));
  const int nq = rule.size();
  BasisTabulation t;
  t.values.resize(nq, m_size);
  t.gradients.assign(nq, Eigen::MatrixXd(m_size, m_dim));
  Eigen::VectorXd phi(m_size);
  double xi[3] = {0.0, 0.0, 0.0};
  for (int q = 0; q < nq; ++q) {
    for (int d = 0; d < m_dim; ++d) xi[d] = rule.points(q, d);
    values_and_gradients(xi, phi.data(), t.gradients[q].data());
    t.values.row(q) = phi.transpose();
  }
  return t;
}

Eigen::MatrixXd LagrangeBasis::reference_nodes() const {
  Eigen::MatrixXd x(m_size, m_dim);
  for (int i = 0; i < m_size; ++i)
    for (int d = 0; d < m_dim; ++d)
      x(i, d) = static_cast<double>(m_lattice[4 * i + d + 1]) / m_degree;
  return x;
}

std::vector<std::array<int, 4>> LagrangeBasis::node_lattice() const {
  std::vector<std::array<int, 4>> lattice(m_size);
  for (int i = 0; i < m_size; ++i)
    for (int j = 0; j < 4; ++j) lattice[i][j] = m_lattice[4 * i + j];
  return lattice;
}

std::vector<std::array<int, 3>> LagrangeBasis::monomial_exponents() const {
  std::vector<std::array<int, 3>> exps(m_size);
  for (int m = 0; m < m_size; ++m)
    for (int j = 0; j < 3; ++j) exps[m][j] = m_exponents[3 * m + j];
  return exps;
}

}  // namespace curvefem::fem
