#include "fem/problems/constraints.hpp"

#include <algorithm>

#include "meshing/core/error.hpp"

namespace curvefem::fem {

int Constraints::num_fixed() const {
  return static_cast<int>(std::count(fixed.begin(), fixed.end(), 1));
}

void for_each_boundary_dof(const FunctionSpace& space, const std::vector<char>& faces,
                           const PointFilter& where, const std::function<void(int)>& visit) {
  CF_VERIFY(faces.size() == space.boundary_faces.size(), "boundary face flags do not match");
  const auto& lattice = lagrange_lattice(CellKind::tetrahedron, space.degree);
  const int n = static_cast<int>(space.cell_dofs.cols());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (!faces[f]) continue;
    const auto [cell, j] = space.boundary_faces[f];
    for (int l = 0; l < n; ++l) {
      if (lattice[l][j] != 0) continue;  // not on the face opposite vertex j
      const int d = space.cell_dofs(cell, l);
      if (where && !where(space.dof_points.row(d).transpose())) continue;
      visit(d);
    }
  }
}

Eigen::VectorXd solve_constrained(const SparseMatrix& K, const Eigen::VectorXd& F,
                                  const Constraints& c, const LinearSolverOptions& options,
                                  LinearSolveInfo* info) {
  const int n = static_cast<int>(K.rows());
  CF_VERIFY(static_cast<int>(c.fixed.size()) == n && c.values.size() == n,
            "constraints do not match the system size");
  std::vector<int> reduced(n, -1);
  int m = 0;
  for (int i = 0; i < n; ++i)
    if (!c.fixed[i]) reduced[i] = m++;
  Eigen::VectorXd rhs(m);
  for (int i = 0; i < n; ++i)
    if (reduced[i] >= 0) rhs[reduced[i]] = F[i];
  std::vector<Eigen::Triplet<double, int>> entries;
  entries.reserve(static_cast<std::size_t>(K.nonZeros()));
  for (int col = 0; col < n; ++col)
    for (SparseMatrix::InnerIterator it(K, col); it; ++it) {
      const int row = static_cast<int>(it.row());
      if (reduced[row] < 0) continue;
      if (reduced[col] >= 0)
        entries.emplace_back(reduced[row], reduced[col], it.value());
      else
        rhs[reduced[row]] -= it.value() * c.values[col];
    }
  SparseMatrix Kff(m, m);
  Kff.setFromTriplets(entries.begin(), entries.end());
  const Eigen::VectorXd uf = solve_spd(Kff, rhs, options, info);
  Eigen::VectorXd u(n);
  for (int i = 0; i < n; ++i) u[i] = reduced[i] >= 0 ? uf[reduced[i]] : c.values[i];
  return u;
}

}  // namespace curvefem::fem
