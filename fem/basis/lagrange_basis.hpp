// Equispaced Lagrange bases of degree p = 1..4 on the reference triangle and tetrahedron, for
// p-FEM: values and gradients from committed monomial tables (fem/basis/generated/, written by
// tools/gen_lagrange_basis.py).
//
// Conventions: reference simplex and local node order are those of meshing/core/lagrange_nodes.hpp
// (vertices, edges, faces, interior; entities lexicographic; descending lexicographic barycentric
// index inside an entity). Basis function i is 1 at lagrange_reference_nodes(kind, p).row(i) and 0
// at the other nodes. φ_i(x) = Σ_m C(i, m) x^a_m y^b_m z^c_m with the exact coefficients C of the
// generated table; evaluation computes the monomials once and applies one small dense matvec.
//
// Shapes: a reference point has dim() coordinates (2 triangle, 3 tetrahedron; an
// Eigen::Vector3d argument uses its first dim() entries); values #n; gradients #n × dim
// (column-major, so a raw buffer of n·dim doubles is Eigen::Map<Eigen::MatrixXd>(buf, n, dim)).
// The object is immutable after construction and safe to share between threads.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/lagrange_nodes.hpp"

namespace curvefem::fem {

/// Basis values and gradients at the points of a quadrature rule, for assembly loops.
struct BasisTabulation {
  Eigen::MatrixXd values;                  ///< #q × #n: values(q, i) = φ_i(x_q)
  std::vector<Eigen::MatrixXd> gradients;  ///< #q entries, each #n × dim: ∇φ_i(x_q) in row i
};

class LagrangeBasis {
 public:
  /// InputError if degree ∉ 1..4.
  LagrangeBasis(CellKind kind, int degree);

  CellKind kind() const { return m_kind; }
  int degree() const { return m_degree; }
  int dim() const { return m_dim; }
  /// Number of basis functions = number of nodes.
  int size() const { return m_size; }

  /// phi[i] = φ_i(xi); xi has dim() entries, phi has size() entries.
  void values(const double* xi, double* phi) const;
  /// Column-major #n × dim: grad[d * size() + i] = ∂φ_i/∂x_d (xi).
  void gradients(const double* xi, double* grad) const;
  /// Both at once (shares the monomial powers); phi may be nullptr.
  void values_and_gradients(const double* xi, double* phi, double* grad) const;

  /// #n values at xi (first dim() entries used).
  Eigen::VectorXd values(const Eigen::Vector3d& xi) const;
  /// #n × dim gradients at xi.
  Eigen::MatrixXd gradients(const Eigen::Vector3d& xi) const;

  /// Values and gradients at every point of `rule` (rule.dimension() must equal dim()).
  BasisTabulation tabulate(const QuadratureRule& rule) const;

  /// #n × dim reference coordinates of the nodes (canonical order).
  Eigen::MatrixXd reference_nodes() const;
  /// Barycentric multi-indices of the nodes as stored in the generated table (for cross-checks
  /// against curvefem::lagrange_lattice).
  std::vector<std::array<int, 4>> node_lattice() const;
  /// Exponents (a, b, c) of the monomial basis, in the generator's order.
  std::vector<std::array<int, 3>> monomial_exponents() const;

 private:
  CellKind m_kind;
  int m_degree;
  int m_dim;
  int m_size;
  const int* m_lattice;          // generated: #n × 4
  const int* m_exponents;        // generated: #n × 3
  const double* m_coefficients;  // generated: #n × #n, row-major
};

}  // namespace curvefem::fem
