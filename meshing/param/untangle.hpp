// Removing the self-intersections of a genus-0 surface (thesis §3.2.3, Fig. 3.9): a
// conformalized mean curvature flow (Kazhdan, Solomon and Ben-Chen 2012) runs until the surface is
// embedded, then the flow is undone with the tet scaffold (scaf3d.hpp): every vertex is pulled
// back toward its input position (or, with the ARAP way back, toward the input's shape) while the
// solid and the space around it stay positively tetrahedralized, so the surface returns close to
// the input and never meets itself.
//
// The flow: (M_t − δ L) X_{t+1} = M_t X_t, L the cotangent stiffness of the *input* (fixed: the
// "conformalized" flow, which does not pinch), M_t the lumped mass of the current surface; after
// each step the surface is translated and scaled back to the input's centroid and area. δ is
// relative to the input's area (δ · A). The self-intersecting pairs are counted exactly
// (meshing/check) after every step; the flow stops at the first step without any.
// Where the flow has not separated the surface after `max_flow_steps`, a MeshingError names the
// pairs left. The flow is meant for genus 0: for a higher genus it is still tried (a small local
// crossing may well separate), with a warning naming the genus.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/param/scaf3d.hpp"

namespace curvefem::meshing::param {

struct UntangleOptions {
  double flow_step = 1e-3;  ///< δ relative to the input's area
  int max_flow_steps = 200;
  /// The way back (scaf3d_deform from the flowed surface). Its targets are the input's vertices
  /// (`way_back_targets`); with deform.arap_weight > 0 the surface ARAP term toward the input's
  /// shape (its rest: the input) is added, the thesis' way back (Fig. 3.9).
  Deform3dOptions deform;
  /// false: no positional targets, the ARAP term alone pulls the surface back (needs
  /// deform.arap_weight > 0; InputError otherwise).
  bool way_back_targets = true;
};

struct UntangleResult {
  Eigen::MatrixXd V;            ///< the untangled surface (the input's faces)
  Eigen::MatrixXd flowed;       ///< the embedded flowed surface the way back started from
  int input_pairs = 0;          ///< self-intersecting pairs of the input
  int genus = 0;                ///< (2 − χ) / 2 summed over components (a warning when > 0)
  std::vector<int> flow_pairs;  ///< after each flow step
  Deform3dResult back;          ///< the scaffold deformation toward the input
  double max_distance_rel = 0;  ///< max ‖V − V_input‖ over vertices / the input's bbox diagonal
  double mean_distance_rel = 0;
  /// Shape against the input: |ℓ − ℓ₀| / ℓ₀ over the surface edges (mean and max).
  double edge_length_error_mean = 0, edge_length_error_max = 0;
  double flow_seconds = 0;
};

/// Throws InputError for an input without self-intersection (nothing to do) or with a degenerate
/// face, MeshingError when the flow leaves crossings after max_flow_steps.
UntangleResult untangle_surface(const SurfaceMesh& input, const UntangleOptions& options = {});

}  // namespace curvefem::meshing::param
