// What a problem's kept operator (FactorizationCache's assembly slot,
// fem/solvers/linear_solver.hpp) was assembled on: the mesh and space objects and their sizes, and
// the quadrature degree. A kept operator is reused only on the same ones; the mesh must not change
// while a cache holds it, and the coefficients each problem compares itself (poisson.cpp,
// elasticity.cpp).
#pragma once

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

}  // namespace curvefem::fem
