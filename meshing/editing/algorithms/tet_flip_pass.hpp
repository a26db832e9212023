#pragma once
// The flip pass shared by harmonic triangulation and quality flips: 2-3 on interior faces, 3-2
// and 4-4 (both diagonals) on interior edges, renewed around every success. What a flip must
// achieve is the mesh's `invariants` hook; this file only schedules.

#include <Eigen/Core>
#include <functional>

#include "meshing/editing/scheduler.hpp"

namespace curvefem::meshing::editing {

/// Runs the flip pass over every live tet of `mesh`. `priority` (optional): larger first.
PassStats run_flip_pass(TetMesh& mesh, const std::function<Eigen::Vector3d(Id)>& position,
                        int threads,
                        const std::function<double(const TetMesh::Tuple&)>& priority = {});

/// Exact orientation: true iff (b-a)x(c-a)·(d-a) > 0 (CGAL's filtered predicate).
bool positively_oriented(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                         const Eigen::Vector3d& c, const Eigen::Vector3d& d);

}  // namespace curvefem::meshing::editing
