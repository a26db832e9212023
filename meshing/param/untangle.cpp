// Conformalized mean curvature flow until embedded, then back toward the input inside a scaffold.
#include "meshing/param/untangle.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/Geometry>
#include <Eigen/Sparse>
#include <cmath>
#include <map>
#include <set>

#include "meshing/check/self_intersections.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::meshing::param {

namespace {

// Cotangent stiffness K (positive semi-definite: K = −L) of the surface (V, F).
Eigen::SparseMatrix<double> cotangent_stiffness(const Eigen::MatrixXd& V,
                                                const Eigen::MatrixXi& F) {
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(std::size_t(F.rows()) * 12);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d p[3] = {V.row(F(f, 0)).transpose(), V.row(F(f, 1)).transpose(),
                                  V.row(F(f, 2)).transpose()};
    const double area2 = (p[1] - p[0]).cross(p[2] - p[0]).norm();
    if (!(area2 > 0)) {
      ErrorContext ctx;
      ctx.face = f;
      throw InputError("untangle: degenerate face (zero area)", ctx);
    }
    for (int k = 0; k < 3; ++k) {
      // The angle at corner k weighs the opposite edge (i, j): ½ cot = ½ (a·b) / |a × b|.
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      const Eigen::Vector3d a = p[i] - p[k], b = p[j] - p[k];
      const double w = 0.5 * a.dot(b) / area2;
      const int vi = F(f, i), vj = F(f, j);
      trip.emplace_back(vi, vj, -w);
      trip.emplace_back(vj, vi, -w);
      trip.emplace_back(vi, vi, w);
      trip.emplace_back(vj, vj, w);
    }
  }
  Eigen::SparseMatrix<double> K(V.rows(), V.rows());
  K.setFromTriplets(trip.begin(), trip.end());
  return K;
}

// Lumped (barycentric) vertex areas and the total area.
Eigen::VectorXd lumped_mass(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, double& total) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(V.rows());
  total = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    total += area;
    for (int k = 0; k < 3; ++k) m[F(f, k)] += area / 3;
  }
  return m;
}

// Σ over connected components of (2 − χ) / 2, χ = V − E + F of the component (closed surface).
int surface_genus(const Eigen::MatrixXi& F, int nv) {
  std::vector<int> link(static_cast<std::size_t>(nv));
  for (int v = 0; v < nv; ++v) link[std::size_t(v)] = v;
  auto find = [&](int v) {
    while (link[std::size_t(v)] != v)
      v = link[std::size_t(v)] = link[std::size_t(link[std::size_t(v)])];
    return v;
  };
  std::set<std::pair<int, int>> edges;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      edges.emplace(std::min(a, b), std::max(a, b));
      link[std::size_t(find(a))] = find(b);
    }
  std::map<int, long long> chi;  // per component root: V − E + F
  std::vector<char> used(static_cast<std::size_t>(nv), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    chi[find(F(f, 0))] += 1;
    for (int k = 0; k < 3; ++k) used[std::size_t(F(f, k))] = 1;
  }
  for (const auto& [a, b] : edges) chi[find(a)] -= 1;
  for (int v = 0; v < nv; ++v)
    if (used[std::size_t(v)]) chi[find(v)] += 1;
  long long genus = 0;
  for (const auto& [root, c] : chi) genus += std::max(0LL, (2 - c) / 2);
  return int(genus);
}

// Area-weighted centroid.
Eigen::RowVector3d centroid(const Eigen::MatrixXd& V, const Eigen::VectorXd& mass) {
  return (mass.asDiagonal() * V).colwise().sum() / mass.sum();
}

}  // namespace

UntangleResult untangle_surface(const SurfaceMesh& input, const UntangleOptions& options) {
  UntangleResult result;
  const Eigen::MatrixXd& V0 = input.V;
  const Eigen::MatrixXi& F = input.F;
  if (!options.way_back_targets && !(options.deform.arap_weight > 0))
    throw InputError(
        "untangle: without targets the way back needs the ARAP term (an ARAP weight > 0)");
  result.input_pairs = check::count_self_intersecting_pairs(V0, F);
  if (result.input_pairs == 0)
    throw InputError("untangle: the surface has no self-intersection: nothing to do");
  result.genus = surface_genus(F, int(V0.rows()));
  if (result.genus > 0)
    log::warn("untangle: the surface has genus ", result.genus,
              "; the flow separates genus-0 surfaces, a higher genus may keep its crossings");
  Stopwatch flow_watch;
  const Eigen::SparseMatrix<double> K = cotangent_stiffness(V0, F);
  double area0 = 0;
  const Eigen::VectorXd m0 = lumped_mass(V0, F, area0);
  const Eigen::RowVector3d c0 = centroid(V0, m0);
  const double delta = options.flow_step * area0;
  Eigen::MatrixXd X = V0;
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  llt.cholmod().print = 0;
  int pairs = result.input_pairs;
  for (int step = 1; step <= options.max_flow_steps && pairs > 0; ++step) {
    double area = 0;
    const Eigen::VectorXd m = lumped_mass(X, F, area);
    Eigen::SparseMatrix<double> A = delta * K;
    for (Eigen::Index i = 0; i < A.rows(); ++i) A.coeffRef(i, i) += m[i];
    if (step == 1) llt.analyzePattern(A);
    llt.factorize(A);
    if (llt.info() != Eigen::Success)
      throw SolverError("untangle: CHOLMOD factorisation of the flow step failed");
    const Eigen::MatrixXd rhs = m.asDiagonal() * X;
    X = llt.solve(rhs);
    // Back to the input's centroid and area: the flow shrinks and drifts.
    double area_now = 0;
    const Eigen::VectorXd m_now = lumped_mass(X, F, area_now);
    const Eigen::RowVector3d c = centroid(X, m_now);
    const double s = std::sqrt(area0 / area_now);
    X = ((X.rowwise() - c) * s).rowwise() + c0;
    pairs = check::count_self_intersecting_pairs(X, F);
    result.flow_pairs.push_back(pairs);
    log::debug("untangle: flow step ", step, ": ", pairs, " self-intersecting pairs");
  }
  result.flow_seconds = flow_watch.seconds();
  if (pairs > 0)
    throw MeshingError("untangle: " + std::to_string(pairs) +
                       " self-intersecting pairs are left after " +
                       std::to_string(options.max_flow_steps) +
                       " flow steps (a genus-0 surface separates; is this one of higher genus?)");
  result.flowed = X;
  log::info("untangle: ", result.input_pairs, " self-intersecting pairs removed by ",
            result.flow_pairs.size(), " flow steps in ", result.flow_seconds, " s");
  // The way back: every vertex pulled toward its input position inside the scaffold.
  std::vector<PositionTarget> targets;
  if (options.way_back_targets) {
    targets.reserve(std::size_t(V0.rows()));
    for (Eigen::Index v = 0; v < V0.rows(); ++v) targets.push_back({int(v), V0.row(v).transpose()});
  }
  SurfaceMesh flowed = input;
  flowed.V = X;
  Deform3dOptions back = options.deform;
  if (back.arap_weight > 0 && back.arap_rest.size() == 0) back.arap_rest = V0;  // the input's shape
  result.back = scaf3d_deform(flowed, targets, back);
  result.V = result.back.V;
  const double diag = (V0.colwise().maxCoeff() - V0.colwise().minCoeff()).norm();
  const Eigen::VectorXd d = (result.V - V0).rowwise().norm();
  result.max_distance_rel = d.maxCoeff() / diag;
  result.mean_distance_rel = d.mean() / diag;
  double sum = 0;
  int edges = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a > b) continue;  // each edge of a closed surface once (from the face with a < b)
      const double l0 = (V0.row(a) - V0.row(b)).norm(),
                   l = (result.V.row(a) - result.V.row(b)).norm();
      const double e = std::abs(l - l0) / l0;
      sum += e;
      result.edge_length_error_max = std::max(result.edge_length_error_max, e);
      ++edges;
    }
  result.edge_length_error_mean = edges > 0 ? sum / edges : 0.0;
  return result;
}

}  // namespace curvefem::meshing::param
