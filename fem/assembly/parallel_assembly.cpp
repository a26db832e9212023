#include "fem/assembly/parallel_assembly.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>

namespace curvefem::fem {

void assemble_cells(int num_cells, int local_size, const ElementKernel& compute,
                    const SparsePattern& pattern, const Eigen::MatrixXi& cell_dofs, int block_size,
                    std::vector<double>* values, Eigen::VectorXd* load) {
  const long long per_cell = static_cast<long long>(local_size) * local_size;
  const int block = static_cast<int>(std::clamp<long long>(8'000'000 / per_cell, 64, 4096));
  std::vector<Eigen::MatrixXd> Ke(block, Eigen::MatrixXd(local_size, local_size));
  std::vector<Eigen::VectorXd> Fe(block, Eigen::VectorXd(local_size));
  const int nodes = static_cast<int>(cell_dofs.cols());
  for (int first = 0; first < num_cells; first += block) {
    const int count = std::min(block, num_cells - first);
    tbb::parallel_for(tbb::blocked_range<int>(0, count, 16), [&](const tbb::blocked_range<int>& r) {
      for (int i = r.begin(); i < r.end(); ++i) {
        Ke[i].setZero();
        Fe[i].setZero();
        compute(first + i, Ke[i], Fe[i]);
      }
    });
    for (int i = 0; i < count; ++i) {
      const int cell = first + i;
      if (values) pattern.scatter(cell, Ke[i], *values);
      if (load)
        for (int a = 0; a < nodes; ++a)
          for (int j = 0; j < block_size; ++j)
            (*load)[cell_dofs(cell, a) * block_size + j] += Fe[i][a * block_size + j];
    }
  }
}

}  // namespace curvefem::fem
