#pragma once
// P_T at h = 0 on saved shell fibers (shell_fibers.hpp): the input point where the fiber of a
// point (f, u, v) of the middle surface crosses the input (thesis §4.4; DESIGN.md §2, "BoundaryMap
// φ": φ⁻¹ without the shell code).
//
// (u, v) are barycentric coordinates in prism f's face rotated to its smallest vertex id (point =
// (1 − u − v)·c0 + u·c1 + v·c2). The search follows meshing/shell/projection.cpp step by step: the
// fiber polyline's 6 segments from the middle outwards, the first one meeting a candidate face
// of the prism gives the answer (the crossing closest to its start); at a pinched corner the fiber
// is the pinch point, whose input point is taken; a fiber shrunk toward a pinch point by rounding
// is solved on the fiber scaled up about that point. Every decision (does a segment meet a face,
// does a point lie on one, does a segment cross a wedge) is taken with the exact predicates of
// meshing/core/exact_predicates.hpp, which decide as the shell projection's CGAL predicates do,
// and every crossing is computed by the same floating-point operations: on the same fiber both
// give the same face and bits, up to the choice between faces that share the crossing point.
// Agreement with ShellProjection::project is tested in tests/mapping.
//
// Positions are input points (Σ bary_k · V[F(t, k)] of the input, not of the reference copy).
// Fibers built on a refinement of the input (ShellFibers::refined) cross the refined surface; the
// crossing is reported in the input face that holds it.
// The object owns its data; queries are const and thread-safe.
#include <Eigen/Core>
#include <array>
#include <optional>
#include <vector>

#include "meshing/core/shell_fibers.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem {

/// A point of the dense input surface on a fiber.
struct FiberCrossing {
  int face = -1;                  ///< input face
  Eigen::Vector3d bary{0, 0, 0};  ///< barycentric coordinates in that face (input vertex order)
  Eigen::Vector3d position{0, 0, 0};
};

class FiberProjection {
 public:
  /// Throws InputError when `fibers` is malformed or names input vertices or faces `input` does
  /// not have.
  FiberProjection(ShellFibers fibers, const SurfaceMesh& input);

  /// P_T(f, u, v) at h = 0; nullopt when f is out of range or the fiber misses the input.
  std::optional<FiberCrossing> project(int face, double u, double v) const;
  /// The fiber of (face, u, v) from base to top: its 7 corners (index 3 on the middle triangle).
  std::array<Eigen::Vector3d, 7> fiber(int face, double u, double v) const;

  const ShellFibers& fibers() const { return m_fibers; }

 private:
  std::array<Eigen::Vector3d, 7> fiber_at(int f, const std::array<double, 3>& w) const;
  std::array<Eigen::Vector3d, 3> triangle(int t) const;  // reference copy of input face t
  FiberCrossing input_point(int t, const Eigen::Vector3d& bary) const;
  bool contains(int t, const Eigen::Vector3d& x) const;
  std::vector<int> star(int f, const Eigen::Vector3d& x) const;
  std::optional<FiberCrossing> segment_hit(int f, const Eigen::Vector3d& a,
                                           const Eigen::Vector3d& b) const;
  std::optional<FiberCrossing> at_pinch(int f, const Eigen::Vector3d& x) const;
  std::optional<FiberCrossing> near_pinch(int f, int s, const std::array<double, 3>& w) const;

  ShellFibers m_fibers;
  Eigen::MatrixXd m_input_V;  // the input (m_V, m_F: the refined surface if any)
  Eigen::MatrixXi m_input_F;
  Eigen::MatrixXd m_V;                      // input vertices
  Eigen::MatrixXd m_reference;              // reference copy of the input vertices
  Eigen::MatrixXi m_F;                      // input faces
  std::vector<Eigen::Vector3d> m_lo, m_hi;  // box of each reference face
};

}  // namespace curvefem
