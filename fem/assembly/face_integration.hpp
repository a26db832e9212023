// Quadrature on the curved boundary faces of a tetrahedral mesh: the face of cell c opposite
// local vertex j is the image of the reference face; points, surface measure and outward unit
// normal come from the order-k cell map restricted to that face.
#pragma once

#include <Eigen/Core>
#include <functional>

#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

struct FacePoint {
  Eigen::Vector3d x;       ///< physical point
  Eigen::Vector3d normal;  ///< outward unit normal
  double ds_w = 0.0;       ///< surface measure × weight
  const double* phi;       ///< space basis values at the point (num_lagrange_nodes(tet, p))
};

/// Calls `visit(face index, cell, point)` for every quadrature point (exact to `degree` on the
/// reference triangle) of every boundary face whose flag is set.
void for_each_face_point(const LagrangeMesh& mesh, const FunctionSpace& space,
                         const std::vector<char>& selected, int degree,
                         const std::function<void(int face, int cell, const FacePoint&)>& visit);

}  // namespace curvefem::fem
