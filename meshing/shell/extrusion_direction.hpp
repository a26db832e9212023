#pragma once
// Per-vertex extrusion directions of the prismatic shell (thesis §4.2; reference-notes §3.1).
//
// For a vertex v with incident faces N(v) and unit face normals n_f, the direction is the
// normalized solution of   min ‖x‖²  subject to  n_f · x ≥ 1 for every f ∈ N(v),
// solved exactly: the "most visible normal". A double-precision active-set solve is accepted only
// when its KKT conditions verify with a margin; otherwise CGAL's QP solver with an exact number
// type decides (see extrusion_direction.cpp).
// v is singular when the program is infeasible (no direction sees all its faces) or when the
// normalized direction has n_f · d < tolerance for some incident face (too flat). A degenerate
// (zero-area) incident face has a zero normal, so its vertices are singular.

#include <Eigen/Core>
#include <vector>

namespace curvefem::meshing::shell {

struct ExtrusionDirections {
  Eigen::MatrixXd N;  // #V × 3, unit directions; zero rows for singular/unreferenced vertices
  std::vector<char>
      singular;  // #V, 1 for singular vertices (unreferenced vertices are not singular)
  int singular_count = 0;
};

// V: #V × 3, F: #F × 3, closed or open, consistently oriented (outward normals).
// Parallel over vertices (oneTBB); the result does not depend on the thread count.
// Throws InputError on non-finite coordinates or out-of-range vertex ids.
ExtrusionDirections extrusion_directions(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                         double tolerance = 1e-2);

// The same program for one vertex: face normals (unit) in, direction out; false if singular
// (direction is then zero).
bool most_visible_direction(const std::vector<Eigen::Vector3d>& normals, double tolerance,
                            Eigen::Vector3d& direction);

namespace detail {

// The two halves of most_visible_direction, exposed for tests and benchmarks.
enum class FastOutcome { direction, singular, undecided };

// Double-precision active-set solve with KKT verification. `undecided` (direction zero) when the
// verification fails or is ambiguous: most_visible_direction then calls the exact solver.
FastOutcome most_visible_direction_fast(const std::vector<Eigen::Vector3d>& normals,
                                        double tolerance, Eigen::Vector3d& direction);

// CGAL's exact QP solver (CGAL::Gmpzf) only.
bool most_visible_direction_exact(const std::vector<Eigen::Vector3d>& normals, double tolerance,
                                  Eigen::Vector3d& direction);

}  // namespace detail

}  // namespace curvefem::meshing::shell
