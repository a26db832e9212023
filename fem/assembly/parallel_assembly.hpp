// Element loop of every assembly: element matrices/vectors are computed in parallel (oneTBB,
// blocks of cells), then added into the global CSR values and load vector serially in cell order,
// so the result is bit-identical for any number of threads.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "fem/assembly/sparse_pattern.hpp"

namespace curvefem::fem {

/// compute(cell, Ke, Fe): Ke is local_size², Fe local_size, both zeroed before the call. Either
/// output may be skipped by passing a null `values` / `load`; `pattern` is needed (non-null)
/// only with `values`.
using ElementKernel = std::function<void(int cell, Eigen::MatrixXd& Ke, Eigen::VectorXd& Fe)>;

/// active_cells (size num_cells), if given: only the cells flagged are computed and scattered.
void assemble_cells(int num_cells, int local_size, const ElementKernel& compute,
                    const SparsePattern* pattern, const Eigen::MatrixXi& cell_dofs, int block_size,
                    double* values, Eigen::VectorXd* load,
                    const std::vector<char>* active_cells = nullptr);

/// The cells with at least one DOF flagged in `dofs` (size: the DOF count).
std::vector<char> cells_touching(const Eigen::MatrixXi& cell_dofs, const std::vector<char>& dofs);

}  // namespace curvefem::fem
