#include "fem/assembly/parallel_assembly.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace curvefem::fem {

namespace {

// Cells by their smallest DOF (a counting sort, stable): with DOFs numbered in a spatial order
// (function_space.hpp) consecutive cells then scatter into nearby rows, whatever order the mesh
// file gave its cells.
std::vector<int> locality_order(const Eigen::MatrixXi& cell_dofs, int num_cells) {
  std::vector<int> first(static_cast<std::size_t>(num_cells));
  int max_dof = 0;
  for (int c = 0; c < num_cells; ++c) {
    first[std::size_t(c)] = cell_dofs.row(c).minCoeff();
    max_dof = std::max(max_dof, first[std::size_t(c)]);
  }
  std::vector<int> start(static_cast<std::size_t>(max_dof) + 2, 0);
  for (int c = 0; c < num_cells; ++c) ++start[std::size_t(first[std::size_t(c)]) + 1];
  for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
  std::vector<int> order(static_cast<std::size_t>(num_cells));
  for (int c = 0; c < num_cells; ++c)
    order[std::size_t(start[std::size_t(first[std::size_t(c)])]++)] = c;
  return order;
}

}  // namespace

void assemble_cells(int num_cells, int local_size, const ElementKernel& compute,
                    const SparsePattern& pattern, const Eigen::MatrixXi& cell_dofs, int block_size,
                    double* values, Eigen::VectorXd* load) {
  const long long per_cell = static_cast<long long>(local_size) * local_size;
  const int block = static_cast<int>(std::clamp<long long>(8'000'000 / per_cell, 64, 4096));
  std::vector<Eigen::MatrixXd> Ke(block, Eigen::MatrixXd(local_size, local_size));
  std::vector<Eigen::VectorXd> Fe(block, Eigen::VectorXd(local_size));
  const int nodes = static_cast<int>(cell_dofs.cols());
  const std::vector<int> order = locality_order(cell_dofs, num_cells);
  for (int first = 0; first < num_cells; first += block) {
    const int count = std::min(block, num_cells - first);
    tbb::parallel_for(tbb::blocked_range<int>(0, count, 16), [&](const tbb::blocked_range<int>& r) {
      for (int i = r.begin(); i < r.end(); ++i) {
        Ke[i].setZero();
        Fe[i].setZero();
        compute(order[std::size_t(first + i)], Ke[i], Fe[i]);
      }
    });
    for (int i = 0; i < count; ++i) {
      const int cell = order[std::size_t(first + i)];
      if (values) pattern.scatter(cell, Ke[i], values);
      if (load)
        for (int a = 0; a < nodes; ++a)
          for (int j = 0; j < block_size; ++j)
            (*load)[cell_dofs(cell, a) * block_size + j] += Fe[i][a * block_size + j];
    }
  }
}

}  // namespace curvefem::fem
