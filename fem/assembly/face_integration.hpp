// Quadrature on the curved boundary faces of a tetrahedral mesh: the face of cell c opposite
// local vertex j is the image of the reference face; points, surface measure and outward unit
// normal come from the order-k cell map restricted to that face.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

struct FacePoint {
  Eigen::Vector3d x;       ///< physical point
  Eigen::Vector3d normal;  ///< outward unit normal
  double ds_w = 0.0;       ///< surface measure × weight
  const double* phi;       ///< space basis values at the point (num_lagrange_nodes(tet, p))
};

/// Every quadrature point of the selected boundary faces at once, in the order of
/// for_each_face_point (faces in boundary_faces order, then rule points), so that boundary data
/// can be evaluated in parallel and summed serially in a fixed order.
/// Shapes: x, normal #points × 3; ds_w, face, cell, basis_row #points; basis
/// (4 · #rule points) × num_lagrange_nodes(tet, p), row-major: basis.row(basis_row[k]) holds the
/// space basis values at point k.
struct FacePoints {
  Eigen::MatrixXd x, normal;
  Eigen::VectorXd ds_w;
  std::vector<int> face, cell, basis_row;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> basis;
  /// Only with face_points(..., with_gradients = true): per point, the physical gradients of the
  /// space basis (num_lagrange_nodes(tet, p) × 3).
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, 3>> gradients;

  int size() const { return static_cast<int>(face.size()); }
  FacePoint point(int k) const;
};

/// The quadrature points (exact to `degree` on the reference triangle) of every boundary face
/// whose flag is set; faces are processed in parallel (oneTBB), the result is independent of the
/// thread count.
FacePoints face_points(const LagrangeMesh& mesh, const FunctionSpace& space,
                       const std::vector<char>& selected, int degree, bool with_gradients = false);

/// Calls `evaluate(k, x)` in parallel (oneTBB) for every point k of `points` where `where` is
/// empty or true, and returns those points' flags. `evaluate` writes its result to its own slot
/// k; summing the results afterwards in point order keeps assembly independent of the threads.
std::vector<char> evaluate_at_face_points(
    const FacePoints& points, const std::function<bool(const Eigen::Vector3d&)>& where,
    const std::function<void(int k, const Eigen::Vector3d& x)>& evaluate);

/// Calls `visit(face index, cell, point)` for every quadrature point (exact to `degree` on the
/// reference triangle) of every boundary face whose flag is set.
void for_each_face_point(const LagrangeMesh& mesh, const FunctionSpace& space,
                         const std::vector<char>& selected, int degree,
                         const std::function<void(int face, int cell, const FacePoint&)>& visit);

}  // namespace curvefem::fem
