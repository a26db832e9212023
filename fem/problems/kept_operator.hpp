// What a problem's kept operator (FactorizationCache's assembly slot,
// fem/solvers/linear_solver.hpp) was assembled on: the mesh and space objects and their sizes, and
// the quadrature degree. A kept operator is reused only on the same ones; the mesh must not change
// while a cache holds it, and the coefficients each problem compares itself (poisson.cpp,
// elasticity.cpp).
// Also shared by the problems: AssemblyParts, what one assembly computes.
#pragma once

#include <vector>

#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

struct KeptDiscretization {
  const LagrangeMesh* mesh;
  const FunctionSpace* space;
  int cells, dofs, degree, quadrature;
  KeptDiscretization(const LagrangeMesh& m, const FunctionSpace& s, int q)
      : mesh(&m),
        space(&s),
        cells(m.num_cells()),
        dofs(s.num_dofs),
        degree(s.degree),
        quadrature(q) {}
  bool same(const LagrangeMesh& m, const FunctionSpace& s, int q) const {
    return mesh == &m && space == &s && cells == m.num_cells() && dofs == s.num_dofs &&
           degree == s.degree && quadrature == q;
  }
};

/// What an assembly computes: K and F (whole), F alone, or K's rows of some DOFs alone (a
/// distributed solve's part: fem/problems/constraints.hpp, solve_constrained_by_rows).
struct AssemblyParts {
  bool matrix = true, load = true;
  const std::vector<char>* rows = nullptr;  ///< with matrix: the DOFs whose rows are assembled
  /// Whether K's entry (da·b+i, db·b+j) is assembled: K is stored by columns and symmetric, so
  /// column db holds the rows of DOF db, kept when they are assembled.
  bool keeps(int db) const { return matrix && (!rows || (*rows)[std::size_t(db)]); }
};
inline constexpr AssemblyParts k_load_only{false, true, nullptr};

}  // namespace curvefem::fem
