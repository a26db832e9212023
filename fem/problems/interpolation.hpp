// Moving finite element fields between spaces on the same mesh, and the Lagrange output mesh of
// order m = max(p, k) that VTU/MSH writers take (its nodes are the degree-m DOF points, shared
// between cells, so ParaView sees one continuous curved field).
#pragma once

#include <Eigen/Core>

#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

/// Values (c per DOF, DOF-major) of the field `u` of space `from` at the DOF points of `to`;
/// returns #to.dofs × c.
Eigen::MatrixXd interpolate_field(const FunctionSpace& from, const Eigen::VectorXd& u, int c,
                                  const FunctionSpace& to);

/// The order-m Lagrange mesh whose nodes are the DOF points of `space` (degree m).
LagrangeMesh lagrange_mesh_of_space(const LagrangeMesh& mesh, const FunctionSpace& space);

}  // namespace curvefem::fem
