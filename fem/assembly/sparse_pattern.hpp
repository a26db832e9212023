// Compressed sparse row pattern of a FEM matrix from the cells' DOF lists (block size b: DOF d
// owns unknowns b·d .. b·d+b−1), and deterministic scattering of element matrices into it.
// Scattering is serial and in cell order, so results do not depend on the thread count that
// computed the element matrices. A pattern may hold the rows of some DOFs only (`row_dofs`): the
// other rows are empty and scatter() skips them, so a matrix can be assembled by blocks of rows
// (the distributed solves' parts, fem/solvers/distributed.hpp) without the whole pattern.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace curvefem::fem {

class SparsePattern {
 public:
  /// row_dofs (size num_dofs), if given: only the rows of the DOFs flagged are in the pattern
  /// (all their columns); the others are empty.
  SparsePattern(const Eigen::MatrixXi& cell_dofs, int num_dofs, int block_size,
                const std::vector<char>* row_dofs = nullptr);
  int rows() const { return static_cast<int>(m_row_ptr.size()) - 1; }
  long long nonzeros() const { return static_cast<long long>(m_col.size()); }
  /// Index into the value array of (row, col); -1 if not in the pattern.
  long long find(int row, int col) const;
  /// Adds the (b·n) × (b·n) element matrix of `cell` (local unknown order: node-major,
  /// component-minor) into `values` (nonzeros() entries, in the pattern's order); rows left out
  /// of the pattern are skipped.
  void scatter(int cell, const Eigen::MatrixXd& local, double* values) const;
  /// A compressed column-major Eigen matrix with this pattern and zero values (the pattern is
  /// symmetric, so CSR of A is CSC of Aᵀ = A); assemblies scatter into its valuePtr() in place.
  /// With row_dofs, column j holds row j of the symmetric matrix for the rows kept, and is empty
  /// for the others.
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> zero_matrix() const;

 private:
  const Eigen::MatrixXi& m_cell_dofs;
  int m_block;
  std::vector<int> m_row_ptr;
  std::vector<int> m_col;
};

}  // namespace curvefem::fem
