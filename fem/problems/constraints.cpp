#include "fem/problems/constraints.hpp"

#include <algorithm>
#include <utility>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"

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

namespace {

/// The solver options of the reduced system: the near-nullspace coordinates of the full system
/// (one row per node, blocks of 3) restricted to the free unknowns. When every node is either
/// free or fixed in all its components, the free nodes' coordinates (blocks stay aligned);
/// otherwise (components fixed separately) block size 1 and the six rigid-body modes restricted
/// to the free rows as explicit vectors.
LinearSolverOptions reduced_options(const LinearSolverOptions& options,
                                    const std::vector<int>& reduced, int m) {
  LinearSolverOptions out = options;
  const Eigen::MatrixXd& xyz = options.near_nullspace_coordinates;
  const int n = static_cast<int>(reduced.size());
  if (xyz.size() == 0) {
    if (options.block_size > 1 && m % options.block_size != 0) out.block_size = 1;
    return out;
  }
  CF_VERIFY(options.block_size == 3 && xyz.cols() == 3 && 3 * xyz.rows() == n,
            "near-nullspace coordinates do not match the system (#unknowns/3 x 3)");
  const int nodes = static_cast<int>(xyz.rows());
  bool aligned = true;
  for (int d = 0; d < nodes && aligned; ++d) {
    const int free = (reduced[3 * d] >= 0) + (reduced[3 * d + 1] >= 0) + (reduced[3 * d + 2] >= 0);
    aligned = free == 0 || free == 3;
  }
  if (aligned) {
    out.near_nullspace_coordinates.resize(m / 3, 3);
    for (int d = 0; d < nodes; ++d)
      if (reduced[3 * d] >= 0) out.near_nullspace_coordinates.row(reduced[3 * d] / 3) = xyz.row(d);
    return out;
  }
  out.block_size = 1;
  out.near_nullspace_coordinates.resize(0, 3);
  out.near_nullspace_vectors = Eigen::MatrixXd::Zero(m, 6);
  const Eigen::RowVector3d center = xyz.colwise().mean();
  for (int d = 0; d < nodes; ++d) {
    const Eigen::RowVector3d y = xyz.row(d) - center;
    // Translations e_i and rotations e_a × y: (e_a × y)_i = ε_iab y_b.
    const double rot[3][3] = {{0, y[2], -y[1]}, {-y[2], 0, y[0]}, {y[1], -y[0], 0}};  // [i][a]
    for (int i = 0; i < 3; ++i) {
      const int r = reduced[3 * d + i];
      if (r < 0) continue;
      out.near_nullspace_vectors(r, i) = 1.0;
      for (int a = 0; a < 3; ++a) out.near_nullspace_vectors(r, 3 + a) = rot[i][a];
    }
  }
  return out;
}

// The reduced solve; `owned`, if set, is K itself, released once K_ff and the right-hand side
// are built (before the solver's own copies and preconditioner).
Eigen::VectorXd reduce_and_solve(const SparseMatrix& K, const Eigen::VectorXd& F,
                                 const Constraints& c, const LinearSolverOptions& options,
                                 LinearSolveInfo* info, SparseMatrix* owned) {
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
  // Kff in place: reduced[] increases, so the kept rows of a kept column stay sorted once
  // renumbered; no triplets and no sort (which cost a copy of K and a transposition: 1-3 s and
  // 16 bytes per entry on 250k-unknown P2 elasticity). Fixed columns move to the right-hand side.
  Eigen::Index nnz = 0;
  for (int col = 0; col < n; ++col) {
    if (reduced[col] < 0) continue;
    for (SparseMatrix::InnerIterator it(K, col); it; ++it) nnz += reduced[it.row()] >= 0;
  }
  SparseMatrix Kff(m, m);
  Kff.resizeNonZeros(nnz);
  int* outer = Kff.outerIndexPtr();
  int* inner = Kff.innerIndexPtr();
  double* value = Kff.valuePtr();
  Eigen::Index k = 0;
  outer[0] = 0;
  for (int col = 0; col < n; ++col) {
    const int rc = reduced[col];
    for (SparseMatrix::InnerIterator it(K, col); it; ++it) {
      const int rr = reduced[it.row()];
      if (rr < 0) continue;
      if (rc >= 0) {
        inner[k] = rr;
        value[k++] = it.value();
      } else {
        rhs[rr] -= it.value() * c.values[col];
      }
    }
    if (rc >= 0) outer[rc + 1] = static_cast<int>(k);
  }
  CF_VERIFY(k == nnz, "reduced system: entry count mismatch");
  if (owned) release(*owned);
  // Kff is this function's own: handed over, a distributed solve frees it once distributed.
  const Eigen::VectorXd uf =
      solve_spd(std::move(Kff), rhs, reduced_options(options, reduced, m), info);  // swapped in
  Eigen::VectorXd u(n);
  for (int i = 0; i < n; ++i) u[i] = reduced[i] >= 0 ? uf[reduced[i]] : c.values[i];
  return u;
}

}  // namespace

Eigen::VectorXd solve_constrained(const SparseMatrix& K, const Eigen::VectorXd& F,
                                  const Constraints& c, const LinearSolverOptions& options,
                                  LinearSolveInfo* info) {
  return reduce_and_solve(K, F, c, options, info, nullptr);
}

Eigen::VectorXd solve_constrained(SparseMatrix&& K, const Eigen::VectorXd& F, const Constraints& c,
                                  const LinearSolverOptions& options, LinearSolveInfo* info) {
  SparseMatrix owned;
  owned.swap(K);  // not std::move: Eigen's SparseMatrix would copy (linear_solver.hpp)
  return reduce_and_solve(owned, F, c, options, info, &owned);
}

Eigen::VectorXd solve_constrained_by_rows(const distributed::RowAssembly& system,
                                          const Eigen::VectorXd& F, const Constraints& c,
                                          const LinearSolverOptions& options,
                                          LinearSolveInfo* info) {
  const int n = static_cast<int>(F.size());
  CF_VERIFY(static_cast<int>(c.fixed.size()) == n && c.values.size() == n,
            "constraints do not match the system size");
  std::vector<int> reduced(static_cast<std::size_t>(n), -1);
  int m = 0;
  for (int i = 0; i < n; ++i)
    if (!c.fixed[std::size_t(i)]) reduced[std::size_t(i)] = m++;
  LinearSolveInfo local;
  LinearSolveInfo& out = info ? *info : local;
  out = {};
  if (m == 0) return c.values;
  const bool direct = options.type == SolverType::direct;  // "auto" is cg over several ranks
  const Eigen::VectorXd uf = distributed::solve_by_rows(
      system, F, c.values, reduced, m, reduced_options(options, reduced, m), direct, out);
  log::info("linear solve (", out.method, ", ", out.ranks, " ranks, assembled by rows): ", m,
            " unknowns, ", out.iterations, " iterations, relative residual ", out.relative_residual,
            ", setup ", out.setup_s, " s (of it the rows' assembly ", out.assembly_s, " s), solve ",
            out.solve_s, " s");
  Eigen::VectorXd u(n);
  for (int i = 0; i < n; ++i)
    u[i] = reduced[std::size_t(i)] >= 0 ? uf[reduced[std::size_t(i)]] : c.values[i];
  return u;
}

}  // namespace curvefem::fem
