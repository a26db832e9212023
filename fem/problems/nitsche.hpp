// Dirichlet conditions on boundary faces that a point filter selects only in part.
//
// A Dirichlet selection painted on the dense input acts point-wise (the condition's `where`), so
// a coarse face can be Dirichlet on one part and Neumann on the other. Fixing the DOFs that pass
// the filter and leaving the others free is inconsistent on such a face: a free DOF's test
// function is non-zero on the Dirichlet part, where the weak form then has no flux term, and the
// error it causes is O(1) next to the interface. These *partial* faces are imposed weakly
// instead, by Nitsche's symmetric method on the face quadrature points that pass the filter:
//   −∫ κ ∂u/∂n v − ∫ κ ∂v/∂n (u − g) + ∫ β (u − g) v,   β = 4 (p + 1)(p + 3) κ / h,
// (elasticity: σ(u)n and σ(v)n on the constrained components, κ → λ + 2μ), h = 3 |T| / |F| of
// the face's cell with its corners (the inverse inequality on a tetrahedron, with a margin of 4).
// A face that every one of its DOFs and quadrature points passes stays strong; a face none of
// whose quadrature points passes keeps its passing DOFs fixed (a selection narrower than the
// mesh resolution still constrains a node).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "fem/assembly/face_integration.hpp"
#include "fem/problems/boundary_conditions.hpp"
#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

/// The faces of one Dirichlet condition, split.
struct DirichletFaceSplit {
  std::vector<char> strong;  ///< per boundary face: fix the DOFs that pass the filter
  FacePoints points;         ///< quadrature points (with gradients) of the partial faces
  std::vector<char> used;    ///< per point of `points`: passes the filter
  int partial_faces = 0;
};

/// Splits the selected faces of a condition (faces, where). Without a filter, or with `nodal`,
/// every selected face is strong and there is no partial face.
DirichletFaceSplit split_dirichlet_faces(const LagrangeMesh& mesh, const FunctionSpace& space,
                                         const std::vector<char>& faces, const PointFilter& where,
                                         PartialDirichlet mode);

/// h = 3 |T| / |F| with the corners of `cell` and of its face opposite local vertex j (at least
/// 1e-3 √|F|: a curved cell's corners can be nearly coplanar).
double nitsche_length(const LagrangeMesh& mesh, int cell, int j);

/// β / κ = 4 (p + 1)(p + 3) / h.
double nitsche_penalty(int degree, double h);

}  // namespace curvefem::fem
