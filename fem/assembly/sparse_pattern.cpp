#include "fem/assembly/sparse_pattern.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>

namespace curvefem::fem {

SparsePattern::SparsePattern(const Eigen::MatrixXi& cell_dofs, int num_dofs, int block_size,
                             const std::vector<char>* row_dofs)
    : m_cell_dofs(cell_dofs), m_block(block_size) {
  if (row_dofs && static_cast<int>(row_dofs->size()) != num_dofs)
    throw std::invalid_argument("SparsePattern: row_dofs does not match num_dofs");
  const int nc = static_cast<int>(cell_dofs.rows()), n = static_cast<int>(cell_dofs.cols());
  // The cells' DOF lists row by row (the matrix is column-major), then DOF → cells.
  std::vector<int> dofs(static_cast<std::size_t>(nc) * n);
  for (int c = 0; c < nc; ++c)
    for (int l = 0; l < n; ++l) dofs[std::size_t(c) * n + l] = cell_dofs(c, l);
  std::vector<int> start(static_cast<std::size_t>(num_dofs) + 1, 0);
  for (int d : dofs) ++start[std::size_t(d) + 1];
  for (int d = 0; d < num_dofs; ++d) start[d + 1] += start[d];
  std::vector<int> cells(static_cast<std::size_t>(start.back())),
      fill(start.begin(), start.end() - 1);
  for (int c = 0; c < nc; ++c)
    for (int l = 0; l < n; ++l)
      cells[std::size_t(fill[std::size_t(dofs[std::size_t(c) * n + l])]++)] = c;
  // Per DOF the union of its cells' DOFs: a marker drops repeats, so only the distinct
  // neighbours are sorted.
  std::vector<int> row_ptr(static_cast<std::size_t>(num_dofs) + 1, 0), col,
      marker(std::size_t(num_dofs), -1);
  const std::size_t kept_rows =
      row_dofs ? static_cast<std::size_t>(std::count(row_dofs->begin(), row_dofs->end(), 1))
               : static_cast<std::size_t>(num_dofs);
  col.reserve(kept_rows * std::size_t(std::min(n * 4, 256)));
  for (int d = 0; d < num_dofs; ++d) {
    const std::size_t row_start = col.size();
    if (row_dofs && !(*row_dofs)[std::size_t(d)]) {
      row_ptr[std::size_t(d) + 1] = static_cast<int>(col.size());
      continue;
    }
    for (int i = start[std::size_t(d)]; i < start[std::size_t(d) + 1]; ++i) {
      const int* list = dofs.data() + std::size_t(cells[std::size_t(i)]) * n;
      for (int l = 0; l < n; ++l)
        if (marker[std::size_t(list[l])] != d) {
          marker[std::size_t(list[l])] = d;
          col.push_back(list[l]);
        }
    }
    std::sort(col.begin() + static_cast<std::ptrdiff_t>(row_start), col.end());
    row_ptr[std::size_t(d) + 1] = static_cast<int>(col.size());
  }
  const int b = m_block;
  if (b == 1) {
    m_row_ptr = std::move(row_ptr);
    m_col = std::move(col);
    return;
  }
  m_row_ptr.assign(static_cast<std::size_t>(num_dofs) * b + 1, 0);
  for (int d = 0; d < num_dofs; ++d)
    for (int i = 0; i < b; ++i)
      m_row_ptr[std::size_t(d) * b + i + 1] =
          (row_ptr[std::size_t(d) + 1] - row_ptr[std::size_t(d)]) * b;
  for (std::size_t r = 0; r + 1 < m_row_ptr.size(); ++r) m_row_ptr[r + 1] += m_row_ptr[r];
  m_col.resize(std::size_t(m_row_ptr.back()));
  for (int d = 0; d < num_dofs; ++d)
    for (int i = 0; i < b; ++i) {
      int k = m_row_ptr[std::size_t(d) * b + i];
      for (int r = row_ptr[std::size_t(d)]; r < row_ptr[std::size_t(d) + 1]; ++r)
        for (int j = 0; j < b; ++j) m_col[std::size_t(k++)] = col[std::size_t(r)] * b + j;
    }
}

long long SparsePattern::find(int row, int col) const {
  const auto first = m_col.begin() + m_row_ptr[row], last = m_col.begin() + m_row_ptr[row + 1];
  const auto it = std::lower_bound(first, last, col);
  return (it != last && *it == col) ? static_cast<long long>(it - m_col.begin()) : -1;
}

void SparsePattern::scatter(int cell, const Eigen::MatrixXd& local, double* values) const {
  const int n = static_cast<int>(m_cell_dofs.cols()), b = m_block;
  // The cell's DOFs in increasing order (with their local index): every row is then one forward
  // walk through its sorted columns instead of a binary search per entry.
  constexpr int k_max_local = 64;
  std::array<std::pair<int, int>, k_max_local> sorted;
  if (n > k_max_local) throw std::logic_error("SparsePattern::scatter: too many DOFs per cell");
  for (int c = 0; c < n; ++c) {
    std::pair<int, int> e{m_cell_dofs(cell, c), c};
    int k = c;
    for (; k > 0 && sorted[k - 1].first > e.first; --k) sorted[k] = sorted[k - 1];
    sorted[k] = e;
  }
  for (int a = 0; a < n; ++a)
    for (int i = 0; i < b; ++i) {
      const int row = m_cell_dofs(cell, a) * b + i;
      if (m_row_ptr[row] == m_row_ptr[row + 1]) continue;  // a row left out (row_dofs)
      const int* col = m_col.data() + m_row_ptr[row];
      double* value = values + m_row_ptr[row];
      const int ai = a * b + i;
      for (int c = 0; c < n; ++c) {
        const int col0 = sorted[c].first * b;
        while (*col < col0) ++col;  // found: the pattern holds every pair of a cell's DOFs
        const long long k = col - m_col.data() - m_row_ptr[row];
        const int lc = sorted[c].second * b;
        for (int j = 0; j < b; ++j) value[k + j] += local(ai, lc + j);
      }
    }
}

Eigen::SparseMatrix<double, Eigen::ColMajor, int> SparsePattern::zero_matrix() const {
  const int n = rows();
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> A(n, n);
  A.resizeNonZeros(static_cast<Eigen::Index>(m_col.size()));
  std::copy(m_row_ptr.begin(), m_row_ptr.end(), A.outerIndexPtr());
  std::copy(m_col.begin(), m_col.end(), A.innerIndexPtr());
  std::fill_n(A.valuePtr(), m_col.size(), 0.0);
  return A;
}

}  // namespace curvefem::fem
