// Continuous Lagrange space of degree p = 1..4 on a tetrahedral mesh of any geometric order k.
//
// DOFs sit at the equispaced lattice points of degree p of every cell (canonical local order of
// meshing/core/lagrange_nodes.hpp). A DOF is identified globally by its entity's global vertex ids
// together with its barycentric weights on them, sorted by global vertex id, so neighbours that
// share an edge or a face agree on every DOF whatever their local orientations (this is what keeps
// p ≥ 3 edge and face DOFs consistent). Geometry and space are independent (iso-, sub-,
// super-parametric): DOF points are the images of the reference lattice under the order-k map.
// The mesh's corner nodes must be its cells' first four canonical nodes (they are, by definition).
// DOFs are numbered in the order they are first met over the cells taken along a Morton curve of
// their centroids, so that neighbouring DOFs get neighbouring numbers whatever the mesh file's cell
// order (a Gmsh volume mesh's is spatially random); assembly and solvers touch memory locally.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

/// A boundary face: cell id and the local vertex opposite the face (0..3).
struct BoundaryFace {
  int cell = 0;
  int opposite = 0;
};

struct FunctionSpace {
  int degree = 1;
  int num_dofs = 0;
  Eigen::MatrixXi cell_dofs;      ///< #cells × num_lagrange_nodes(tet, degree)
  Eigen::MatrixXd dof_points;     ///< #dofs × 3, physical positions
  std::vector<char> on_boundary;  ///< per DOF
  std::vector<BoundaryFace> boundary_faces;
};

/// Throws InputError if degree ∉ 1..4 or the mesh is not made of tetrahedra.
FunctionSpace build_function_space(const LagrangeMesh& mesh, int degree);

/// Boundary faces of a tet mesh (faces with one incident cell), in cell order.
std::vector<BoundaryFace> find_boundary_faces(const LagrangeMesh& mesh);

}  // namespace curvefem::fem
