// Per-vertex extrusion directions: min ‖x‖² s.t. n_f · x ≥ 1 (see the header).
//
// Duality. With y* the minimum-norm point of the convex hull of the normals, the program is
// feasible iff y* ≠ 0, its solution is x* = y* / ‖y*‖², and min_f n_f · (y*/‖y*‖) = ‖y*‖, attained
// by the active faces (those whose normal lies on the face of the hull that contains y*). In KKT
// terms, y* = Σ μ_f n_f with convex weights μ gives the multipliers λ_f = 2 μ_f / ‖y*‖² ≥ 0 of
// the primal, and primal feasibility n_f · x ≥ 1 reads g_f = (n_f − y*) · y* ≥ 0.
//
// 1. Fast path (double): Gilbert–Johnson–Keerthi / Wolfe active-set iterations on the normals.
//    The active set W (≤ 4 normals) carries y = the minimum-norm point of conv(W), computed on the
//    faces of W through QR of the edge vectors (differences of normals, which keeps y accurate
//    when normals are nearly equal). A normal below the plane {z : z · y = ‖y‖²} joins W (the
//    lowest first); the loop stops when no normal is below it by more than its rounding bound.
//    The gap g_f is evaluated as (n_f − n_a) · y with n_a the nearest active normal, so its
//    rounding error is proportional to ‖n_f − n_a‖ (exact duplicates are exactly on the plane).
// 2. Verification (a-priori error bound, in units of the direction d = y / ‖y‖):
//    - μ ≥ 0 and Σ μ = 1 hold by construction (faces with a negative weight are rejected);
//    - rounding of y on a face with edge-matrix condition number κ: 8 ε (1 + 2κ);
//    - every normal not certainly above the plane (|g_f| within its bound, or below it by a
//      negligible amount) adds the displacement it could cause if it were active: the smaller of
//      (tilt) 2 (bound − g_f) / its distance to the affine hulls of ≤ 2 active normals, and
//      (perturbation) ‖n_f − n_a‖ (1 + 2‖y‖ / smallest singular value of the active face);
//    the sum divided by ‖y‖ must be ≤ 2.5e-13, the vertex is undecided otherwise, or when
//    min_f n_f · d is within that error of `tolerance`, or when 64 iterations do not converge, or
//    when an iteration does not decrease ‖y‖. These bounds are estimates, not proofs; they were
//    checked against the exact solver on every vertex of the 19 meshes of shared/data/dev
//    (largest difference 1.2e-14) and on the random cones of test_shell_predicates.
// Face normals are unit cross products of the two edges at the corner opposite the longest edge
// (the least cancellation), normalized with Eigen's stableNormalized; a zero cross product gives
// a zero normal, which makes the program infeasible.

#include "meshing/shell/extrusion_direction.hpp"

#include <CGAL/Gmpzf.h>
#include <CGAL/QP_functions.h>
#include <CGAL/QP_models.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::meshing::shell {

namespace {

using Eigen::Vector3d;

constexpr double k_eps = std::numeric_limits<double>::epsilon();
constexpr int k_max_iterations = 64;
constexpr double k_noise_factor = 8.0;  // rounding bound of y: k_noise_factor · ε · (1 + 2κ)
constexpr double k_direction_error = 2.5e-13;  // accepted a-priori error of the fast direction
constexpr double k_negligible = 1e-14;         // relative displacement not worth an iteration
constexpr double k_max_face_condition = 1e12;  // faces above this are treated as degenerate

// Minimum-norm point of the affine hull of q[0..k-1], if it lies in their convex hull (all
// barycentric weights ≥ 0) and the points are affinely independent (condition number ≤ limit).
struct FaceProjection {
  Vector3d y;
  std::array<double, 4> weight{};
  double condition = 1.0;  // κ of the edge matrix (1 for points and segments)
  double scale = std::numeric_limits<double>::infinity();  // ~ its smallest singular value
};

bool project_on_face(const std::array<Vector3d, 4>& q, int k, FaceProjection& out) {
  if (k == 1) {
    out.y = q[0];
    out.weight = {1.0, 0, 0, 0};
    out.condition = 1.0;
    return true;
  }
  if (k == 2) {
    const Vector3d e = q[1] - q[0];
    const double ee = e.squaredNorm();
    if (!(ee > 0)) return false;
    const double t = -e.dot(q[0]) / ee;
    if (!(t >= 0 && t <= 1)) return false;
    out.y = q[0] + t * e;
    out.weight = {1.0 - t, t, 0, 0};
    out.condition = 1.0;
    out.scale = std::sqrt(ee);
    return true;
  }
  const int K = k - 1;
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  for (int i = 0; i < K; ++i) E.col(i) = q[i + 1] - q[0];
  Eigen::ColPivHouseholderQR<Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 3>> qr(E.leftCols(K));
  const auto& R = qr.matrixQR();
  const double r0 = std::abs(R(0, 0)), rk = std::abs(R(K - 1, K - 1));
  if (!(rk > 0) || r0 > k_max_face_condition * rk) return false;
  const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1> t = qr.solve(Vector3d(-q[0]));
  double sum = 0;
  for (int i = 0; i < K; ++i) {
    if (!(t(i) >= 0)) return false;
    sum += t(i);
  }
  if (!(sum <= 1)) return false;
  out.weight = {1.0 - sum, 0, 0, 0};
  for (int i = 0; i < K; ++i) out.weight[i + 1] = t(i);
  out.condition = r0 / rk;
  out.scale = rk;
  // A full-dimensional face contains the origin itself.
  out.y = (K == 3) ? Vector3d::Zero() : Vector3d(q[0] + E.leftCols(K) * t);
  return true;
}

struct ActiveSet {
  std::array<int, 4> index{};
  int size = 0;
  Vector3d y = Vector3d::Zero();
  double condition = 1.0;
  double scale = std::numeric_limits<double>::infinity();
};

// Minimum-norm point of conv(active ∪ {n[j]}) over the faces that contain n[j] (the only ones
// that can improve on the current y); the new active set is the support of the best face.
ActiveSet add_to_active_set(const Vector3d* n, const ActiveSet& active, int j) {
  std::array<int, 4> all{};
  int m = 0;
  for (int i = 0; i < active.size; ++i) all[m++] = active.index[i];
  all[m++] = j;
  ActiveSet best;
  double best_norm = std::numeric_limits<double>::infinity();
  const int others = m - 1;
  for (int mask = 0; mask < (1 << others); ++mask) {
    std::array<Vector3d, 4> q;
    std::array<int, 4> ids{};
    int k = 0;
    q[k] = n[j];
    ids[k++] = j;
    for (int i = 0; i < others; ++i) {
      if (mask & (1 << i)) {
        q[k] = n[all[i]];
        ids[k++] = all[i];
      }
    }
    FaceProjection p;
    if (!project_on_face(q, k, p)) continue;
    const double norm = p.y.squaredNorm();
    if (norm < best_norm) {
      best_norm = norm;
      best.size = 0;
      for (int i = 0; i < k; ++i) {
        if (p.weight[i] > 0 || i == 0) best.index[best.size++] = ids[i];
      }
      best.y = p.y;
      best.condition = p.condition;
      best.scale = p.scale;
    }
  }
  return best;
}

detail::FastOutcome solve_fast(const Vector3d* n, int m, double tolerance, Vector3d& direction) {
  using detail::FastOutcome;
  direction.setZero();
  if (m == 0) return FastOutcome::singular;  // no constraint: x = 0
  ActiveSet active;
  active.index[0] = 0;
  active.size = 1;
  active.y = n[0];
  double worst_displacement = 0;
  bool converged = false;
  for (int iteration = 0; iteration < k_max_iterations; ++iteration) {
    const double y_norm = active.y.norm();
    const double y_error = k_noise_factor * k_eps * (1.0 + 2.0 * active.condition);
    if (y_norm + y_error < tolerance * (1.0 - 1e-9)) return FastOutcome::singular;
    if (!(y_norm > 0)) return FastOutcome::undecided;  // tolerance ≤ 0: only exact can tell

    // Gap of every other normal, evaluated from its nearest active normal (rounding ∝ distance).
    // A normal below the plane joins W when the displacement it can cause is not negligible;
    // one within rounding of the plane (or negligibly below it) only enters the error bound.
    int below = -1;
    double below_gap = 0;
    worst_displacement = 0;
    for (int j = 0; j < m; ++j) {
      bool in_active = false;
      int nearest = active.index[0];
      double nearest_distance = std::numeric_limits<double>::infinity();
      for (int a = 0; a < active.size; ++a) {
        const int i = active.index[a];
        if (i == j) in_active = true;
        const double d = (n[j] - n[i]).norm();
        if (d < nearest_distance) {
          nearest_distance = d;
          nearest = i;
        }
      }
      if (in_active || nearest_distance == 0) continue;  // exact duplicates change nothing
      const double gap = (n[j] - n[nearest]).dot(active.y);
      const double bound = y_error * nearest_distance + k_eps * nearest_distance * y_norm;
      if (gap >= bound) continue;  // certainly above the plane: inactive
      // How far y could move if n[j] were active. (a) Tilt: the new face contains n[j] and at
      // most two active normals; its plane tilts by (depth of n[j]) / (distance of n[j] to their
      // affine hull). (b) Perturbation: n[j] is within `nearest_distance` of an active normal,
      // which moves y by at most that distance times (1 + 2‖y‖ / smallest scale of the face).
      double lateral = nearest_distance;
      for (int a = 0; a < active.size; ++a) {
        for (int b = a + 1; b < active.size; ++b) {
          const Vector3d e = n[active.index[b]] - n[active.index[a]];
          const double el = e.norm();
          if (el > 0) {
            lateral = std::min(lateral, (n[j] - n[active.index[a]]).cross(e).norm() / el);
          }
        }
      }
      const double tilt =
          lateral > 0 ? 2.0 * (bound - gap) / lateral : std::numeric_limits<double>::infinity();
      const double perturbation = nearest_distance * (1.0 + 2.0 * y_norm / active.scale);
      const double displacement = std::min(tilt, perturbation);
      if (gap < -bound && displacement > k_negligible * y_norm) {
        if (gap < below_gap) {
          below_gap = gap;
          below = j;
        }
      } else {
        worst_displacement = std::max(worst_displacement, displacement);
      }
    }
    if (below < 0) {
      converged = true;
      break;
    }
    ActiveSet next = add_to_active_set(n, active, below);
    if (!(next.size > 0) || !(next.y.squaredNorm() < active.y.squaredNorm())) {
      return FastOutcome::undecided;  // no progress: rounding dominates
    }
    active = next;
  }
  if (!converged) return FastOutcome::undecided;

  const double y_norm = active.y.norm();
  const double y_error = k_noise_factor * k_eps * (1.0 + 2.0 * active.condition);
  const double direction_error = (y_error + worst_displacement) / y_norm;
  if (!(direction_error <= k_direction_error)) return FastOutcome::undecided;
  const Vector3d d = active.y / y_norm;
  double min_dot = std::numeric_limits<double>::infinity();
  for (int j = 0; j < m; ++j) min_dot = std::min(min_dot, n[j].dot(d));
  if (std::abs(min_dot - tolerance) <= 2 * direction_error + 8 * k_eps) {
    return FastOutcome::undecided;  // the singularity test itself is within the error
  }
  if (min_dot < tolerance) return FastOutcome::singular;
  direction = d;
  return FastOutcome::direction;
}

bool solve_exact(const Vector3d* n, int m, double tolerance, Vector3d& direction) {
  direction.setZero();
  if (m == 0) return false;
  // Rows n_f · x ≥ 1, free variables, objective xᵀ I x (set_d takes the entries of 2D).
  CGAL::Quadratic_program<double> qp(CGAL::LARGER, false, 0, false, 0);
  for (int f = 0; f < m; ++f) {
    for (int c = 0; c < 3; ++c) qp.set_a(c, f, n[f][c]);
    qp.set_b(f, 1.0);
  }
  for (int c = 0; c < 3; ++c) qp.set_d(c, c, 2.0);
  const CGAL::Quadratic_program_solution<CGAL::Gmpzf> solution =
      CGAL::solve_quadratic_program(qp, CGAL::Gmpzf());
  if (solution.is_infeasible() || !solution.is_optimal()) return false;
  Vector3d x;
  auto value = solution.variable_values_begin();
  for (int c = 0; c < 3; ++c, ++value) x[c] = CGAL::to_double(*value);
  const double norm = x.norm();
  if (!(norm > 0) || !std::isfinite(norm)) return false;
  const Vector3d d = x / norm;
  for (int f = 0; f < m; ++f) {
    if (!(n[f].dot(d) >= tolerance)) return false;
  }
  direction = d;
  return true;
}

// Returns true when the vertex is regular; `exact` tells whether the exact solver was needed.
bool solve_vertex(const Vector3d* n, int m, double tolerance, Vector3d& direction, bool& exact) {
  exact = false;
  switch (solve_fast(n, m, tolerance, direction)) {
    case detail::FastOutcome::direction:
      return true;
    case detail::FastOutcome::singular:
      return false;
    case detail::FastOutcome::undecided:
      break;
  }
  exact = true;
  return solve_exact(n, m, tolerance, direction);
}

Vector3d unit_face_normal(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const double lab = (b - a).squaredNorm(), lbc = (c - b).squaredNorm(),
               lca = (a - c).squaredNorm();
  Vector3d cross;
  if (lbc >= lab && lbc >= lca) {
    cross = (b - a).cross(c - a);  // corner a is opposite the longest edge bc
  } else if (lca >= lab) {
    cross = (c - b).cross(a - b);
  } else {
    cross = (a - c).cross(b - c);
  }
  if (cross.cwiseAbs().maxCoeff() == 0) return Vector3d::Zero();  // degenerate face
  return cross.stableNormalized();
}

}  // namespace

namespace detail {

FastOutcome most_visible_direction_fast(const std::vector<Eigen::Vector3d>& normals,
                                        double tolerance, Eigen::Vector3d& direction) {
  return solve_fast(normals.data(), static_cast<int>(normals.size()), tolerance, direction);
}

bool most_visible_direction_exact(const std::vector<Eigen::Vector3d>& normals, double tolerance,
                                  Eigen::Vector3d& direction) {
  return solve_exact(normals.data(), static_cast<int>(normals.size()), tolerance, direction);
}

}  // namespace detail

bool most_visible_direction(const std::vector<Eigen::Vector3d>& normals, double tolerance,
                            Eigen::Vector3d& direction) {
  bool exact = false;
  return solve_vertex(normals.data(), static_cast<int>(normals.size()), tolerance, direction,
                      exact);
}

ExtrusionDirections extrusion_directions(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                         double tolerance) {
  Stopwatch watch;
  const int nv = static_cast<int>(V.rows()), nf = static_cast<int>(F.rows());
  if (V.cols() != 3 || (nf > 0 && F.cols() != 3)) {
    throw InputError("extrusion directions: V must be #V x 3 and F #F x 3");
  }
  for (int v = 0; v < nv; ++v) {
    if (!V.row(v).allFinite()) {
      throw InputError("extrusion directions: non-finite vertex coordinates", {.vertex = v});
    }
  }
  for (int f = 0; f < nf; ++f) {
    for (int c = 0; c < 3; ++c) {
      if (F(f, c) < 0 || F(f, c) >= nv) {
        throw InputError("extrusion directions: vertex id out of range", {.face = f});
      }
    }
  }

  std::vector<Vector3d> face_normal(nf);
  tbb::parallel_for(tbb::blocked_range<int>(0, nf, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int f = r.begin(); f < r.end(); ++f) {
      face_normal[f] = unit_face_normal(V.row(F(f, 0)).transpose(), V.row(F(f, 1)).transpose(),
                                        V.row(F(f, 2)).transpose());
    }
  });

  // Vertex → incident faces (CSR), faces in increasing order.
  std::vector<int> start(nv + 1, 0), incident(3 * static_cast<size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    for (int c = 0; c < 3; ++c) ++start[F(f, c) + 1];
  }
  for (int v = 0; v < nv; ++v) start[v + 1] += start[v];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int f = 0; f < nf; ++f) {
      for (int c = 0; c < 3; ++c) incident[fill[F(f, c)]++] = f;
    }
  }

  ExtrusionDirections out;
  out.N = Eigen::MatrixXd::Zero(nv, 3);
  out.singular.assign(nv, 0);
  std::atomic<int> singular_count{0}, exact_count{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, nv, 256), [&](const tbb::blocked_range<int>& r) {
    std::vector<Vector3d> normals;
    normals.reserve(32);
    int singular_local = 0, exact_local = 0;
    for (int v = r.begin(); v < r.end(); ++v) {
      if (start[v] == start[v + 1]) continue;  // unreferenced
      normals.clear();
      for (int k = start[v]; k < start[v + 1]; ++k) normals.push_back(face_normal[incident[k]]);
      Vector3d d;
      bool exact = false;
      if (solve_vertex(normals.data(), static_cast<int>(normals.size()), tolerance, d, exact)) {
        out.N.row(v) = d.transpose();
      } else {
        out.singular[v] = 1;
        ++singular_local;
      }
      exact_local += exact ? 1 : 0;
    }
    singular_count += singular_local;
    exact_count += exact_local;
  });
  out.singular_count = singular_count.load();
  log::info("extrusion directions: ", nv, " vertices, ", out.singular_count, " singular, ",
            exact_count.load(), " decided by the exact QP, ", watch.seconds(), " s");
  return out;
}

}  // namespace curvefem::meshing::shell
