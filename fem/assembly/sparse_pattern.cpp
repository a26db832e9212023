#include "fem/assembly/sparse_pattern.hpp"

#include <algorithm>

namespace curvefem::fem {

SparsePattern::SparsePattern(const Eigen::MatrixXi& cell_dofs, int num_dofs, int block_size)
    : m_cell_dofs(cell_dofs), m_block(block_size) {
  // DOF → cells, then per DOF the union of its cells' DOFs.
  std::vector<int> start(num_dofs + 1, 0);
  for (int c = 0; c < cell_dofs.rows(); ++c)
    for (int l = 0; l < cell_dofs.cols(); ++l) ++start[cell_dofs(c, l) + 1];
  for (int d = 0; d < num_dofs; ++d) start[d + 1] += start[d];
  std::vector<int> cells(start.back()), fill(start.begin(), start.end() - 1);
  for (int c = 0; c < cell_dofs.rows(); ++c)
    for (int l = 0; l < cell_dofs.cols(); ++l) cells[fill[cell_dofs(c, l)]++] = c;
  std::vector<std::vector<int>> neighbours(num_dofs);
  std::vector<int> scratch;
  for (int d = 0; d < num_dofs; ++d) {
    scratch.clear();
    for (int i = start[d]; i < start[d + 1]; ++i)
      for (int l = 0; l < cell_dofs.cols(); ++l) scratch.push_back(cell_dofs(cells[i], l));
    std::sort(scratch.begin(), scratch.end());
    scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
    neighbours[d] = scratch;
  }
  const int b = m_block;
  m_row_ptr.assign(static_cast<std::size_t>(num_dofs) * b + 1, 0);
  for (int d = 0; d < num_dofs; ++d)
    for (int i = 0; i < b; ++i)
      m_row_ptr[d * b + i + 1] = static_cast<int>(neighbours[d].size()) * b;
  for (std::size_t r = 0; r + 1 < m_row_ptr.size(); ++r) m_row_ptr[r + 1] += m_row_ptr[r];
  m_col.resize(m_row_ptr.back());
  for (int d = 0; d < num_dofs; ++d)
    for (int i = 0; i < b; ++i) {
      int k = m_row_ptr[d * b + i];
      for (int e : neighbours[d])
        for (int j = 0; j < b; ++j) m_col[k++] = e * b + j;
    }
}

long long SparsePattern::find(int row, int col) const {
  const auto first = m_col.begin() + m_row_ptr[row], last = m_col.begin() + m_row_ptr[row + 1];
  const auto it = std::lower_bound(first, last, col);
  return (it != last && *it == col) ? static_cast<long long>(it - m_col.begin()) : -1;
}

void SparsePattern::scatter(int cell, const Eigen::MatrixXd& local,
                            std::vector<double>& values) const {
  const int n = static_cast<int>(m_cell_dofs.cols()), b = m_block;
  for (int a = 0; a < n; ++a)
    for (int i = 0; i < b; ++i) {
      const int row = m_cell_dofs(cell, a) * b + i;
      const int* first = m_col.data() + m_row_ptr[row];
      const int* last = m_col.data() + m_row_ptr[row + 1];
      for (int c = 0; c < n; ++c) {
        // Columns of one DOF are contiguous: one search per (a, c) pair.
        const int col0 = m_cell_dofs(cell, c) * b;
        const int* it = std::lower_bound(first, last, col0);
        const long long base = it - m_col.data();
        for (int j = 0; j < b; ++j) values[base + j] += local(a * b + i, c * b + j);
      }
    }
}

Eigen::SparseMatrix<double, Eigen::ColMajor, int> SparsePattern::matrix(
    const std::vector<double>& values) const {
  const int n = rows();
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> A(n, n);
  A.resizeNonZeros(static_cast<Eigen::Index>(m_col.size()));
  std::copy(m_row_ptr.begin(), m_row_ptr.end(), A.outerIndexPtr());
  std::copy(m_col.begin(), m_col.end(), A.innerIndexPtr());
  std::copy(values.begin(), values.end(), A.valuePtr());
  return A;
}

}  // namespace curvefem::fem
