// The solution back on the dense input (DESIGN.md §1, last mapping stage): for every input vertex
// v, the tet and the reference coordinates of φ(v), a finite element field evaluated there, and
// errors against an exact solution on the dense surface.
//
// Exactness: boundary triangle f of the BoundaryMap has corner nodes that are (through
// boundary_node_to_volume) the corners of a boundary face of one tet, whose face nodes are the
// triangle's nodes; the tet's order-k map restricted to that face is the triangle's map. So
// (u, v) in the triangle becomes ξ = (1−u−v)·ξ_a + u·ξ_b + v·ξ_c in the tet (ξ_a, ξ_b, ξ_c the
// reference vertices matching the triangle's corners) without any inversion.
#pragma once

#include <Eigen/Core>
#include <functional>

#include "fem/space/function_space.hpp"
#include "meshing/core/boundary_map.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::mapping {

/// Where φ(v) sits in the volume mesh, for every input vertex v.
struct SurfaceSamples {
  Eigen::VectorXi cell;  ///< #V: tet of φ(v), -1 for vertices without an image
  Eigen::MatrixXd xi;    ///< #V × 3 reference coordinates in that tet
};

/// Throws MeshingError when a boundary triangle of `map` is not a face of `mesh`.
SurfaceSamples locate_input_vertices(const LagrangeMesh& mesh, const BoundaryMap& map);

/// φ(v) = mesh.map(cell, ξ) per vertex: #V × 3 (NaN rows for vertices without an image).
Eigen::MatrixXd sample_positions(const LagrangeMesh& mesh, const SurfaceSamples& samples);

/// A field of `space` (c values per DOF, DOF-major) at every sample: #V × c (NaN without image).
Eigen::MatrixXd evaluate_on_surface(const fem::FunctionSpace& space, const Eigen::VectorXd& u,
                                    int components, const SurfaceSamples& samples);

/// The field's first-order extension from φ(v) to `targets` row v (usually the input vertex v):
///   u_h(φ(v)) + ∇u_h(φ(v)) · (x_v − φ(v)),
/// ∇u_h taken in the tet of φ(v) (basis gradients through the inverse of the tet's Jacobian at
/// ξ). φ(v) lies on the mesh's boundary, up to the distance bound away from v; evaluating u_h
/// there alone carries an error of ∇u·(φ(v) − v), first order in that distance, which the term
/// removes (second order left). #V × c, NaN rows without an image (or a singular Jacobian).
Eigen::MatrixXd evaluate_on_surface_extended(const LagrangeMesh& mesh,
                                             const fem::FunctionSpace& space,
                                             const Eigen::VectorXd& u, int components,
                                             const SurfaceSamples& samples,
                                             const Eigen::MatrixXd& targets);

/// Errors of values at the input vertices against exact(x_v) evaluated at the *input* vertex
/// positions (the data was pulled from the input, so u_h(φ(v)) approximates u(v); this includes
/// the geometric error of the boundary).
struct SurfaceErrors {
  Eigen::MatrixXd exact;  ///< #V × c
  Eigen::MatrixXd error;  ///< #V × c: value − exact (NaN without image)
  /// sqrt(Σ_v A_v |e_v|²), A_v = a third of the areas of the faces at v (lumped surface L2).
  double l2 = 0;
  double l2_exact = 0;  ///< the same norm of the exact values
  double max = 0;       ///< max_v |e_v| (Euclidean over components)
  int vertices = 0;     ///< vertices with an image (the others are left out)
};
using ExactFn = std::function<void(const Eigen::Vector3d& x, double* values)>;
SurfaceErrors surface_errors(const SurfaceMesh& input, const Eigen::MatrixXd& values,
                             const ExactFn& exact);

}  // namespace curvefem::mapping
