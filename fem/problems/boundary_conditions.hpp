// Boundary data of FEM problems, on the boundary faces of the mesh (FunctionSpace::boundary_faces).
//
// A condition selects boundary faces with one flag per boundary face (in boundary_faces order);
// the front end builds the flags from selections ("all", mesh tags, boxes, ...) and, later, from
// selections painted on the dense input through the bijective map. Dirichlet values are imposed
// strongly at every DOF of a selected face (nodal interpolation at the DOF's physical point).
// Fields and filters may be called concurrently from several threads (volume data in the parallel
// element loop, Neumann/traction data at the face quadrature points): they must be thread-safe.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <vector>

namespace curvefem::fem {

using ScalarField = std::function<double(const Eigen::Vector3d&)>;
/// Optional point filter inside selected faces: a Dirichlet DOF / Neumann quadrature point is
/// used only where it returns true (selections by region act point-wise, not face-wise).
using PointFilter = std::function<bool(const Eigen::Vector3d&)>;
using VectorField = std::function<Eigen::Vector3d(const Eigen::Vector3d&)>;
/// A scalar field at all the quadrature points of one cell at once: x is n_q × 3, values is
/// already sized n_q. Lets the caller evaluate over a batch (pipeline's expressions walk their
/// tree once per batch instead of once per point).
using ScalarBatchField = std::function<void(const Eigen::MatrixXd& x, Eigen::VectorXd& values)>;
/// Boundary data of a face quadrature point x, given also the mesh's outward unit normal n there.
using BoundaryScalarField =
    std::function<double(const Eigen::Vector3d& x, const Eigen::Vector3d& n)>;
using BoundaryVectorField =
    std::function<Eigen::Vector3d(const Eigen::Vector3d& x, const Eigen::Vector3d& n)>;

/// How a Dirichlet condition acts on boundary faces its filter selects only in part
/// (fem/problems/nitsche.hpp).
enum class PartialDirichlet {
  nitsche,  ///< weakly, by Nitsche's method on the selected face quadrature points
  nodal,    ///< the DOFs that pass the filter are fixed, the others stay free
};

struct ScalarDirichlet {
  std::vector<char> faces;
  ScalarField value;
  PointFilter where;
};

/// Flux g = κ ∂u/∂n (Poisson), integrated over the selected faces.
struct ScalarNeumann {
  std::vector<char> faces;
  BoundaryScalarField flux;
  PointFilter where;
};

/// Robin (convective) condition −κ ∂u/∂n = h (u − u∞) on the selected faces: adds ∫ h u v to the
/// bilinear form and ∫ h u∞ v to the load. h must be positive where it acts.
struct ScalarRobin {
  std::vector<char> faces;
  BoundaryScalarField h;      ///< heat transfer coefficient
  BoundaryScalarField u_inf;  ///< ambient value
  PointFilter where;
};

/// Displacement prescribed on the components whose mask entry is true.
struct VectorDirichlet {
  std::vector<char> faces;
  std::array<bool, 3> components{true, true, true};
  VectorField value;
  PointFilter where;
};

/// Traction t = σ n on the selected faces.
struct VectorNeumann {
  std::vector<char> faces;
  BoundaryVectorField traction;
  PointFilter where;
};

}  // namespace curvefem::fem
