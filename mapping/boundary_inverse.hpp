// φ⁻¹: from a physical point on the curved boundary ∂T^k of a tet mesh back to the dense input
// surface M (DESIGN.md §1–2; thesis §4.4 and §5).
//
// Two steps:
//   1. locate: x ↦ (boundary triangle f, u, v) with boundary.map(f, (u, v)) = x. Candidates come
//      from a bounding-volume hierarchy over the curved triangles (node boxes inflated by a
//      margin, since a Lagrange triangle may bulge past its nodes' hull); each candidate is
//      inverted by Gauss–Newton on |T_f(u, v) − x|² with (u, v) clamped to the reference
//      triangle; the candidate with the smallest residual wins, accepted if the residual is at most
//      `tolerance_rel` × the longest bounding-box edge of the boundary nodes.
//   2. pull back: (f, u, v) ↦ input face, barycentric coordinates (input vertex order) and point.
//      Curved pipeline: boundary triangle f is prism f of the coarse shell (its face rotated to
//      the smallest vertex id), so this is P_T(f, u, v) at h = 0, evaluated on the shell's saved
//      fibers (meshing/core/fiber_projection.hpp; they come from the shell through
//      meshing/shell/fibers_of.hpp, or from boundary_map.json through meshing/io). Dense pipeline
//      (φ = identity): boundary triangle f is input face f with the same vertex order, and the
//      input point is x itself. mapping/ needs neither meshing/shell nor meshing/curved.
//
// The object keeps a reference to the input (it must outlive it) and owns copies of the rest.
// Queries are const and thread-safe (the cache of located points is locked).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>

#include "meshing/core/boundary_map.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/shell_fibers.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::mapping {

/// A point of the dense input surface.
struct InputPoint {
  int face = -1;                  ///< input face
  Eigen::Vector3d bary{0, 0, 0};  ///< barycentric coordinates in that face (input vertex order)
  Eigen::Vector3d position{0, 0, 0};
};

/// A point of the curved boundary: reference coordinates (u, v) in boundary triangle `face`.
struct BoundaryPoint {
  int face = -1;
  double u = 0, v = 0;
  double residual = 0;  ///< |T_face(u, v) − x| of the query
};

/// Point location on a surface of Lagrange triangles (any order 1..4).
class TriangleLocator {
 public:
  /// `triangles`: kind triangle. `tolerance_rel`: accepted residual relative to the bbox edge.
  explicit TriangleLocator(const LagrangeMesh& triangles, double tolerance_rel = 1e-8);
  ~TriangleLocator();
  TriangleLocator(TriangleLocator&&) noexcept;
  TriangleLocator& operator=(TriangleLocator&&) noexcept;

  /// The triangle and reference coordinates of x, or nullopt when no triangle passes within the
  /// tolerance.
  std::optional<BoundaryPoint> locate(const Eigen::Vector3d& x) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

class BoundaryInverse {
 public:
  /// Curved pipeline: `map.boundary` triangle f is prism f of `fibers` (same vertex rotation).
  /// Throws InputError when the fibers do not fit the map or the input (sizes, ids).
  BoundaryInverse(const BoundaryMap& map, ShellFibers fibers, const SurfaceMesh& input);
  /// Dense pipeline (φ = identity): boundary triangle f is input face f.
  static BoundaryInverse identity(const SurfaceMesh& input);

  ~BoundaryInverse();
  BoundaryInverse(BoundaryInverse&&) noexcept;
  BoundaryInverse& operator=(BoundaryInverse&&) noexcept;

  /// Step 2 alone: φ⁻¹(f, u, v) when the boundary point is known by its coordinates.
  std::optional<InputPoint> from_boundary(int face, double u, double v) const;
  /// Step 1 alone.
  std::optional<BoundaryPoint> locate(const Eigen::Vector3d& x) const;
  /// φ⁻¹(x) for a physical point on the boundary (cached by the exact bits of x).
  std::optional<InputPoint> operator()(const Eigen::Vector3d& x) const;
  /// As operator(), but throws MeshingError naming the point when x is not on the boundary or its
  /// fiber misses the input.
  InputPoint at(const Eigen::Vector3d& x) const;

 private:
  BoundaryInverse();
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

/// The BoundaryMap of the dense pipeline: boundary = the input triangles (order 1, nodes = input
/// vertices, boundary_node_to_volume = identity, which holds for meshing/tetfill output), every
/// referenced vertex placed at a corner of its first incident face; unreferenced vertices get -1.
BoundaryMap make_identity_boundary_map(const SurfaceMesh& input);

}  // namespace curvefem::mapping
