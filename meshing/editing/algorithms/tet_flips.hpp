#pragma once
// Quality flips of a straight tet mesh on the editing framework: 2-3 on interior faces, 3-2 and
// 4-4 on interior edges, each accepted only if every new tet is positively oriented (exact
// predicate) and the worst conformal AMIPS energy of the new tets is below the worst of the
// tets they replace (minimax). Flips never touch a boundary face or edge, so the boundary
// triangulation and every vertex position are kept exactly; only the interior connectivity
// changes. The pass terminates: each flip strictly lowers the worst energy of its cavity and the
// number of triangulations is finite.

#include <Eigen/Core>

#include "meshing/editing/scheduler.hpp"

namespace curvefem::meshing::editing {

struct FlipOptions {
  int threads = 1;
};

struct FlipResult {
  Eigen::MatrixXi T;  // #T' × 4, positively oriented, same vertices
  double max_energy_before = 0, max_energy_after = 0;
  double mean_energy_before = 0, mean_energy_after = 0;
  PassStats pass;
};

/// Conformal AMIPS of a straight tet against the regular tet: tr(JᵀJ) / (3 det(J)^(2/3)), 1 for
/// the regular tet, +∞ when not positive.
double tet_amips(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 const Eigen::Vector3d& d);

/// V: #V × 3; T: #T × 4 positively oriented (throws MeshingError naming a tet that is not).
FlipResult flip_tets(const Eigen::MatrixXd& V, const Eigen::MatrixXi& T,
                     const FlipOptions& options = {});

}  // namespace curvefem::meshing::editing
