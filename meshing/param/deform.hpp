// One checked deformation (`curvefem deform` and Python's `curvefem.deform`): the request is
// validated, scaf3d_deform (or untangle_surface) runs, and the guarantee is checked by code
// independent of the solver — meshing/check's exact self-intersection count after every iteration
// and at the end, verify_scaf3d on the final tiling.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <vector>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/param/scaf3d.hpp"
#include "meshing/param/untangle.hpp"

namespace curvefem::meshing::param {

struct DeformRequest {
  std::vector<PositionTarget> targets;
  Deform3dOptions options;  ///< its on_iteration is replaced; use `observe`
  bool untangle = false;
  UntangleOptions untangle_options;  ///< its `deform` is `options`
  /// Called after every iteration with the surface and its exact self-intersecting pair count.
  std::function<void(const Deform3dIteration&, const Eigen::MatrixXd&, int pairs)> observe;
};

struct DeformOutcome {
  Deform3dResult result;
  std::optional<UntangleResult> untangle;  ///< with --untangle (its `back` moved to `result`)
  int input_pairs = 0;                     ///< self-intersecting pairs of the input
  int naive_pairs = 0;  ///< of the targets applied as they are (untangle: the input's)
  int max_pairs_over_iterations = 0;
  int final_pairs = 0;
  Deform3dCheck tiling;
  double check_seconds = 0;  ///< the exact checks' time
  bool valid() const { return tiling.ok() && final_pairs == 0 && max_pairs_over_iterations == 0; }
};

/// InputError for a request with nothing to do, untangle with targets or grow, or a
/// self-intersecting input without untangle (naming the pair count); otherwise as scaf3d_deform /
/// untangle_surface.
DeformOutcome deform_checked(const SurfaceMesh& surface, DeformRequest request);

}  // namespace curvefem::meshing::param
