// Initial bijective map of the charts: Tutte's embedding of each disk chart onto a circle
// (thesis §3.2.2 "Initialization"), charts laid out side by side on a grid (§3.3, Fig. 3.8).
//
// Each chart's boundary loop is placed on the unit circle by 3D arc length, counter-clockwise;
// interior UV vertices are convex combinations of their neighbours (Floater: with positive
// weights and a strictly convex boundary the result is an embedding: no flipped triangle). The
// chart is then scaled so that its UV area equals its 3D area, and the charts are put on a
// ⌈√n⌉-column grid with cells 1.25 × the largest chart diameter: no two charts overlap.
#pragma once

#include <Eigen/Core>

#include "meshing/param/cut_mesh.hpp"

namespace curvefem::meshing::param {

enum class TutteWeights {
  uniform,     ///< w_ij = 1
  mean_value,  ///< Floater's mean value weights (tan(α/2) + tan(β/2)) / |x_i − x_j|, from 3D
};

/// #U × 2 UV positions of every UV vertex of `cut`. Throws MeshingError if the linear solve fails.
Eigen::MatrixXd tutte_layout(const CutMesh& cut, TutteWeights weights = TutteWeights::mean_value);

}  // namespace curvefem::meshing::param
