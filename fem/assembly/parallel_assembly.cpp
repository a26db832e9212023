#include "fem/assembly/parallel_assembly.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <stdexcept>

namespace curvefem::fem {

namespace {

// Cells by their smallest DOF (a counting sort, stable): with DOFs numbered in a spatial order
// (function_space.hpp) consecutive cells then scatter into nearby rows, whatever order the mesh
// file gave its cells.
// Only the active cells when a mask is given.
std::vector<int> locality_order(const Eigen::MatrixXi& cell_dofs, int num_cells,
                                const std::vector<char>* active) {
  auto used = [&](int c) { return !active || (*active)[std::size_t(c)]; };
  std::vector<int> first(static_cast<std::size_t>(num_cells));
  int max_dof = 0, count = 0;
  for (int c = 0; c < num_cells; ++c) {
    if (!used(c)) continue;
    first[std::size_t(c)] = cell_dofs.row(c).minCoeff();
    max_dof = std::max(max_dof, first[std::size_t(c)]);
    ++count;
  }
  std::vector<int> start(static_cast<std::size_t>(max_dof) + 2, 0);
  for (int c = 0; c < num_cells; ++c)
    if (used(c)) ++start[std::size_t(first[std::size_t(c)]) + 1];
  for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
  std::vector<int> order(static_cast<std::size_t>(count));
  for (int c = 0; c < num_cells; ++c)
    if (used(c)) order[std::size_t(start[std::size_t(first[std::size_t(c)])]++)] = c;
  return order;
}

}  // namespace

void assemble_cells(int num_cells, int local_size, const ElementKernel& compute,
                    const SparsePattern* pattern, const Eigen::MatrixXi& cell_dofs, int block_size,
                    double* values, Eigen::VectorXd* load, const std::vector<char>* active_cells) {
  if (values && !pattern) throw std::invalid_argument("assemble_cells: values without a pattern");
  if (active_cells && static_cast<int>(active_cells->size()) != num_cells)
    throw std::invalid_argument("assemble_cells: active_cells does not match the cell count");
  const long long per_cell = static_cast<long long>(local_size) * local_size;
  const int block = static_cast<int>(std::clamp<long long>(8'000'000 / per_cell, 64, 4096));
  std::vector<Eigen::MatrixXd> Ke(block, Eigen::MatrixXd(local_size, local_size));
  std::vector<Eigen::VectorXd> Fe(block, Eigen::VectorXd(local_size));
  const int nodes = static_cast<int>(cell_dofs.cols());
  const std::vector<int> order = locality_order(cell_dofs, num_cells, active_cells);
  const int cells = static_cast<int>(order.size());
  for (int first = 0; first < cells; first += block) {
    const int count = std::min(block, cells - first);
    tbb::parallel_for(tbb::blocked_range<int>(0, count, 16), [&](const tbb::blocked_range<int>& r) {
      for (int i = r.begin(); i < r.end(); ++i) {
        Ke[i].setZero();
        Fe[i].setZero();
        compute(order[std::size_t(first + i)], Ke[i], Fe[i]);
      }
    });
    for (int i = 0; i < count; ++i) {
      const int cell = order[std::size_t(first + i)];
      if (values) pattern->scatter(cell, Ke[i], values);
      if (load)
        for (int a = 0; a < nodes; ++a)
          for (int j = 0; j < block_size; ++j)
            (*load)[cell_dofs(cell, a) * block_size + j] += Fe[i][a * block_size + j];
    }
  }
}

std::vector<char> cells_touching(const Eigen::MatrixXi& cell_dofs, const std::vector<char>& dofs) {
  std::vector<char> out(static_cast<std::size_t>(cell_dofs.rows()), 0);
  for (Eigen::Index c = 0; c < cell_dofs.rows(); ++c)
    for (Eigen::Index l = 0; l < cell_dofs.cols() && !out[std::size_t(c)]; ++l)
      out[std::size_t(c)] = dofs[std::size_t(cell_dofs(c, l))];
  return out;
}

}  // namespace curvefem::fem
