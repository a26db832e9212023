// The SCAF iteration: scaffold rebuild, SLIM proxy assembly, CHOLMOD solve, flip-free line search.
#include "meshing/param/scaf.hpp"

#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/param/slim_solve.hpp"
#include "meshing/param/symmetric_dirichlet.hpp"

namespace curvefem::meshing::param {

namespace {

using Mat32 = Eigen::Matrix<double, 3, 2>;
constexpr double k_inf = std::numeric_limits<double>::infinity();

Mat32 gradient_operator(const Eigen::Matrix2d& Dm) {
  Mat32 B;
  B << -1, -1, 1, 0, 0, 1;
  return B * Dm.inverse();
}

// The combined chart + scaffold mesh of one iteration. Rows of X: chart UV vertices, then the
// scaffold's box points (fixed) and Steiner points (free).
struct Problem {
  int n_chart_faces = 0;
  Eigen::MatrixXd X;
  std::vector<int> dof;  // free index per row of X, −1 if fixed
  int n_free = 0;
  std::vector<Eigen::Vector3i> tri;
  std::vector<Mat32> G;
  std::vector<double> weight;  // A_f / A_M on charts, λ on the scaffold
  int slivers = 0;             // scaffold triangles whose rest is the ε equilateral

  // Unknown of triangle t's coordinate l (vertex l % 3, axis l / 3), −1 where fixed.
  std::array<int, 6> unknowns(int t) const {
    std::array<int, 6> row;
    for (int l = 0; l < 6; ++l) {
      const int v = tri[std::size_t(t)][l % 3];
      row[std::size_t(l)] = dof[std::size_t(v)] >= 0 ? 2 * dof[std::size_t(v)] + l / 3 : -1;
    }
    return row;
  }

  Eigen::Matrix2d jacobian(int t, const Eigen::MatrixXd& P) const {
    Eigen::Matrix<double, 3, 2> Q;
    for (int k = 0; k < 3; ++k) Q.row(k) = P.row(tri[t][k]);
    return Q.transpose() * G[t];
  }
};

// Objective E_M + λ Σ_S (D − 4); +∞ if a triangle is not positive. `chart` receives E_M.
double evaluate(const Problem& p, const Eigen::MatrixXd& P, double& chart) {
  double em = 0, es = 0;
  for (int t = 0; t < int(p.tri.size()); ++t) {
    const double d = symmetric_dirichlet(p.jacobian(t, P));
    if (!std::isfinite(d)) {
      chart = k_inf;
      return k_inf;
    }
    if (t < p.n_chart_faces)
      em += p.weight[t] * d;
    else
      es += p.weight[t] * (d - 4.0);
  }
  chart = em;
  return em + es;
}

// Directional derivative of the objective at P along D.
double directional_derivative(const Problem& p, const Eigen::MatrixXd& P,
                              const Eigen::MatrixXd& D) {
  double g = 0;
  for (int t = 0; t < int(p.tri.size()); ++t)
    g += p.weight[t] *
         symmetric_dirichlet_gradient(p.jacobian(t, P)).cwiseProduct(p.jacobian(t, D)).sum();
  return g;
}

// Smallest positive root of a t² + b t + c (c > 0), +∞ if none.
double first_positive_root(double a, double b, double c) {
  if (a == 0) return b < 0 ? -c / b : k_inf;
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return k_inf;
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  double best = k_inf;
  if (q != 0) {
    for (double r : {q / a, c / q})
      if (r > 0) best = std::min(best, r);
  } else if (-b / (2 * a) > 0) {
    best = -b / (2 * a);
  }
  return best;
}

// Largest t such that every triangle stays positive on [0, t) (the first root of its area).
double flip_free_bound(const Problem& p, const Eigen::MatrixXd& P, const Eigen::MatrixXd& D) {
  double t_max = k_inf;
  for (const Eigen::Vector3i& f : p.tri) {
    const Eigen::Vector2d e1 = P.row(f[1]) - P.row(f[0]), e2 = P.row(f[2]) - P.row(f[0]);
    const Eigen::Vector2d d1 = D.row(f[1]) - D.row(f[0]), d2 = D.row(f[2]) - D.row(f[0]);
    auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      return a.x() * b.y() - a.y() * b.x();
    };
    t_max = std::min(
        t_max, first_positive_root(cross(d1, d2), cross(e1, d2) + cross(d1, e2), cross(e1, e2)));
  }
  return t_max;
}

struct SingularRange {
  double lo = k_inf, hi = 0;
};
SingularRange chart_singular_values(const CutMesh& cut, const RestShapes& rest,
                                    const Eigen::MatrixXd& uv) {
  SingularRange r;
  for (int f = 0; f < cut.num_faces(); ++f) {
    Mat32 Q;
    for (int k = 0; k < 3; ++k) Q.row(k) = uv.row(cut.F(f, k));
    const Eigen::Matrix2d J = Q.transpose() * rest.G[f];
    const Eigen::Vector2d s = singular_values(J);
    r.lo = std::min(r.lo, J.determinant() > 0 ? s[1] : 0.0);
    r.hi = std::max(r.hi, s[0]);
  }
  return r;
}

Problem make_problem(const CutMesh& cut, const RestShapes& rest, const Eigen::MatrixXd& uv,
                     const Scaffold& s, double chart_energy_now, double scaffold_weight,
                     bool replace_slivers) {
  Problem p;
  const int nu = cut.num_uv_vertices(), ns = int(s.V.rows()), nf = cut.num_faces();
  p.X.resize(nu + ns, 2);
  p.X.topRows(nu) = uv;
  p.X.bottomRows(ns) = s.V;
  p.dof.assign(std::size_t(nu + ns), -1);
  for (int v = 0; v < nu + ns; ++v)
    if (v < nu || v >= nu + s.num_fixed) p.dof[v] = p.n_free++;
  p.n_chart_faces = nf;
  const double total_area = rest.area.sum();
  for (int f = 0; f < nf; ++f) {
    p.tri.emplace_back(cut.F(f, 0), cut.F(f, 1), cut.F(f, 2));
    p.G.push_back(rest.G[f]);
    p.weight.push_back(rest.area[f] / total_area);
  }
  // ε = l²/4, l = the shortest chart boundary edge now (thesis §3.2.2 "degeneracy prevention").
  double l = k_inf;
  for (const auto& loop : cut.boundary_loops)
    for (std::size_t i = 0; i < loop.size(); ++i)
      l = std::min(l, (uv.row(loop[(i + 1) % loop.size()]) - uv.row(loop[i])).norm());
  const double eps = replace_slivers ? 0.25 * l * l : 0.0;
  const double side = std::sqrt(4 * eps / std::sqrt(3.0));
  Eigen::Matrix2d equilateral;
  equilateral << side, 0.5 * side, 0, 0.5 * std::sqrt(3.0) * side;
  const Mat32 G_eq = gradient_operator(equilateral);
  const double lambda = scaffold_weight * chart_energy_now / std::max<Eigen::Index>(1, s.F.rows());
  for (int f = 0; f < s.F.rows(); ++f) {
    const Eigen::Vector3i t = s.F.row(f).transpose();
    Eigen::Matrix2d Dm;
    Dm.col(0) = (p.X.row(t[1]) - p.X.row(t[0])).transpose();
    Dm.col(1) = (p.X.row(t[2]) - p.X.row(t[0])).transpose();
    p.tri.push_back(t);
    const bool sliver = 0.5 * Dm.determinant() < eps;
    p.slivers += sliver;
    p.G.push_back(sliver ? G_eq : gradient_operator(Dm));
    p.weight.push_back(lambda);
  }
  return p;
}

// The step along D: t from min(1, 0.8 × the flip-free bound) (IterationStats::max_step), halved
// (counted in backtracks) until Armijo holds on E and E_M did not increase, down to
// t_min_factor × max_step. Returns t, or 0 when no step qualifies; e and em receive E and E_M
// there.
double line_search(const Problem& p, const Eigen::MatrixXd& D, double armijo, double t_min_factor,
                   IterationStats& st, double& e, double& em) {
  double em0 = 0;
  const double e0 = evaluate(p, p.X, em0);
  const double slope = directional_derivative(p, p.X, D);
  st.max_step = std::min(1.0, 0.8 * flip_free_bound(p, p.X, D));
  if (!(slope < 0)) return 0;
  double t = st.max_step;
  for (int k = 0; k < 60 && t >= t_min_factor * st.max_step; ++k, t *= 0.5) {
    e = evaluate(p, p.X + t * D, em);
    if (std::isfinite(e) && e <= e0 + armijo * t * slope && em <= em0) return t;
    ++st.backtracks;
  }
  return 0;
}

// Minimiser x* of the SLIM proxy Σ c_f ‖W_f (J_f(x) − R_f)‖² with the fixed rows held.
Eigen::MatrixXd solve_proxy(const Problem& p, double& assemble_s, double& solve_s,
                            double& regularisation) {
  Stopwatch watch;
  const int n = 2 * p.n_free;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(p.tri.size() * 36);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (int t = 0; t < int(p.tri.size()); ++t) {
    Eigen::Matrix2d W, R;
    slim_weights(p.jacobian(t, p.X), W, R);
    const Eigen::Matrix2d WR = W * R;
    Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    for (int i = 0; i < 2; ++i)
      for (int c = 0; c < 2; ++c) {
        Eigen::Matrix<double, 6, 1> a;
        a << W(i, 0) * p.G[t].col(c), W(i, 1) * p.G[t].col(c);
        M.noalias() += p.weight[t] * a * a.transpose();
        b += p.weight[t] * WR(i, c) * a;
      }
    const std::array<int, 6> row = p.unknowns(t);
    for (int l = 0; l < 6; ++l) {
      if (row[l] < 0) continue;
      rhs[row[l]] += b[l];
      for (int m = 0; m < 6; ++m) {
        if (row[m] >= 0)
          trip.emplace_back(row[l], row[m], M(l, m));
        else
          rhs[row[l]] -= M(l, m) * p.X(p.tri[t][m % 3], m / 3);
      }
    }
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(trip.begin(), trip.end());
  assemble_s += watch.seconds();
  watch.reset();
  Eigen::VectorXd x0(n);
  for (int v = 0; v < int(p.dof.size()); ++v)
    if (p.dof[v] >= 0) x0.segment<2>(2 * p.dof[v]) = p.X.row(v).transpose();
  const Eigen::VectorXd x = solve_slim_system(A, rhs, x0, regularisation, "param");
  solve_s += watch.seconds();
  Eigen::MatrixXd target = p.X;
  for (int v = 0; v < int(p.dof.size()); ++v)
    if (p.dof[v] >= 0) target.row(v) << x[2 * p.dof[v]], x[2 * p.dof[v] + 1];
  return target;
}

// The projected Newton direction at p.X: H d = −∇E over the free coordinates, H = Σ c_f Bᵀ
// proj(∂²D/∂J²) B with B the map from the triangle's 6 coordinates to vec(J) (fixed rows held).
// `gradient_norm` receives ‖∇E‖.
Eigen::MatrixXd newton_direction(const Problem& p, double& assemble_s, double& solve_s,
                                 double& regularisation, double& gradient_norm) {
  Stopwatch watch;
  const int n = 2 * p.n_free;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(p.tri.size() * 36);
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(n);
  for (int t = 0; t < int(p.tri.size()); ++t) {
    const Eigen::Matrix2d J = p.jacobian(t, p.X);
    const Eigen::Matrix2d dJ = symmetric_dirichlet_gradient(J);
    const Eigen::Vector4d gJ(dJ(0, 0), dJ(0, 1), dJ(1, 0), dJ(1, 1));
    const Eigen::Matrix4d HJ = symmetric_dirichlet_hessian(J, true);
    // vec(J)[2r + c] = Σ_k X(tri[k], r) G(k, c): coordinate l (vertex l % 3, axis l / 3).
    Eigen::Matrix<double, 4, 6> B = Eigen::Matrix<double, 4, 6>::Zero();
    for (int l = 0; l < 6; ++l)
      for (int c = 0; c < 2; ++c) B(2 * (l / 3) + c, l) = p.G[t](l % 3, c);
    const Eigen::Matrix<double, 6, 6> H = p.weight[t] * B.transpose() * HJ * B;
    const Eigen::Matrix<double, 6, 1> g = p.weight[t] * B.transpose() * gJ;
    const std::array<int, 6> row = p.unknowns(t);
    for (int l = 0; l < 6; ++l) {
      if (row[l] < 0) continue;
      grad[row[l]] += g[l];
      for (int m = 0; m < 6; ++m)
        if (row[m] >= 0) trip.emplace_back(row[l], row[m], H(l, m));
    }
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(trip.begin(), trip.end());
  gradient_norm = grad.norm();
  assemble_s += watch.seconds();
  watch.reset();
  const Eigen::VectorXd d =
      solve_slim_system(A, -grad, Eigen::VectorXd::Zero(n), regularisation, "param (Newton)");
  solve_s += watch.seconds();
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(p.X.rows(), 2);
  for (int v = 0; v < int(p.dof.size()); ++v)
    if (p.dof[v] >= 0) D.row(v) << d[2 * p.dof[v]], d[2 * p.dof[v] + 1];
  return D;
}

}  // namespace

double chart_energy(const CutMesh& cut, const Eigen::MatrixXd& uv) {
  const RestShapes rest = rest_shapes(cut);
  double e = 0;
  for (int f = 0; f < cut.num_faces(); ++f) {
    Mat32 Q;
    for (int k = 0; k < 3; ++k) Q.row(k) = uv.row(cut.F(f, k));
    e += rest.area[f] * symmetric_dirichlet(Q.transpose() * rest.G[f]);
  }
  return e / rest.area.sum();
}

ScafResult scaf_optimize(const CutMesh& cut, const Eigen::MatrixXd& uv0,
                         const ScafOptions& options) {
  CF_VERIFY(uv0.rows() == cut.num_uv_vertices() && uv0.cols() == 2, "uv0 must be #U x 2");
  Stopwatch total;
  double callback_s = 0;
  ScafResult result;
  result.uv = uv0;
  const RestShapes rest = rest_shapes(cut);
  const int nu = cut.num_uv_vertices();
  for (int f = 0; f < cut.num_faces(); ++f) {
    Mat32 Q;
    for (int k = 0; k < 3; ++k) Q.row(k) = uv0.row(cut.F(f, k));
    if (!((Q.transpose() * rest.G[f]).determinant() > 0)) {
      ErrorContext ctx;
      ctx.face = f;
      throw InputError("param: the initial map flips or flattens a triangle", ctx);
    }
  }
  auto report = [&](const IterationStats& st, const Scaffold& s) {
    result.history.push_back(st);
    if (options.on_iteration) {
      Stopwatch cb;
      options.on_iteration(st, result.uv, s);
      callback_s += cb.seconds();
    }
  };
  // An accepted step t along D: the charts move, the iteration's numbers are set, and the
  // scaffold reported with it is the one it optimised, moved with it.
  Scaffold scaffold;
  auto take_step = [&](const Problem& p, const Eigen::MatrixXd& D, double t, double e, double em,
                       IterationStats& st) {
    const Eigen::MatrixXd moved = p.X + t * D;
    result.uv = moved.topRows(nu);
    st.step = t;
    st.energy = em;
    st.objective = e;
    const SingularRange sv = chart_singular_values(cut, rest, result.uv);
    st.min_singular = sv.lo;
    st.max_singular = sv.hi;
    scaffold.V = moved.bottomRows(moved.rows() - nu);
  };
  IterationStats st0;
  Stopwatch watch;
  scaffold = build_scaffold(result.uv, cut.boundary_loops, options.scaffold);
  st0.scaffold_s = watch.seconds();
  st0.energy = chart_energy(cut, result.uv);
  st0.objective = st0.energy;
  const SingularRange sv0 = chart_singular_values(cut, rest, result.uv);
  st0.min_singular = sv0.lo;
  st0.max_singular = sv0.hi;
  st0.scaffold_vertices = int(scaffold.V.rows());
  st0.scaffold_faces = int(scaffold.F.rows());
  report(st0, scaffold);
  log::debug("param: iteration 0 energy ", st0.energy);
  result.stop_reason = "iterations";
  for (int it = 1; it <= options.max_iterations; ++it) {
    Stopwatch iteration;
    IterationStats st;
    st.iteration = it;
    if (it > 1) {
      watch.reset();
      scaffold = build_scaffold(result.uv, cut.boundary_loops, options.scaffold);
      st.scaffold_s = watch.seconds();
    } else {
      st.scaffold_s = st0.scaffold_s;
    }
    const double e_prev = result.history.back().energy;
    // With slivers' rest replaced by the ε equilateral (thesis §3.2.2) the scaffold energy at x_k
    // is positive and the SLIM direction may trade chart energy for it; if no step then lowers
    // both, the iteration is redone with every scaffold rest = its current shape, where the
    // direction is a descent direction of E_M itself.
    Problem p;
    Eigen::MatrixXd D;
    double t = 0, em = 0, e = 0;
    bool accepted = false;
    for (int attempt = 0; attempt < 2 && !accepted; ++attempt) {
      p = make_problem(cut, rest, result.uv, scaffold, e_prev, options.scaffold_weight,
                       attempt == 0);
      if (attempt == 0) st.slivers = p.slivers;
      if (attempt == 1) {
        if (st.slivers == 0) break;  // the same problem again: no use
        ++st.fallbacks;
      }
      const Eigen::MatrixXd target = solve_proxy(p, st.assemble_s, st.solve_s, st.regularisation);
      watch.reset();
      D = target - p.X;
      // The first attempt gives up after 14 halvings (t < 1e-4 t_max: the sliver terms are
      // fighting E_M), the fallback goes on to 1e-12 t_max.
      t = line_search(p, D, options.armijo, attempt == 0 ? 1e-4 : 1e-12, st, e, em);
      accepted = t > 0;
      st.line_search_s += watch.seconds();
    }
    st.lambda = p.weight.size() > std::size_t(p.n_chart_faces) ? p.weight.back() : 0.0;
    st.scaffold_vertices = int(scaffold.V.rows());
    st.scaffold_faces = int(scaffold.F.rows());
    if (!accepted) {
      result.stop_reason = "line search";
      result.converged = true;  // no step lowers the energy along the proxy direction
      log::debug("param: iteration ", it, " stops: no acceptable step");
      break;
    }
    take_step(p, D, t, e, em, st);
    st.seconds = iteration.seconds() + (it == 1 ? st0.scaffold_s : 0.0);
    report(st, scaffold);
    log::debug("param: iteration ", it, " energy ", st.energy, " step ", t, " (max ", st.max_step,
               ") scaffold ", st.scaffold_faces, " faces, ", st.seconds, " s");
    if ((e_prev - em) / e_prev < options.tolerance) {
      result.converged = true;
      result.stop_reason = "tolerance";
      break;
    }
  }
  // The projected Newton phase from the SLIM result (ScafOptions::newton_iterations).
  if (options.newton_iterations > 0) result.newton_stop_reason = "iterations";
  for (int k = 0; k < options.newton_iterations; ++k) {
    Stopwatch iteration;
    IterationStats st;
    st.iteration = result.history.back().iteration + 1;
    st.newton = true;
    watch.reset();
    scaffold = build_scaffold(result.uv, cut.boundary_loops, options.scaffold);
    st.scaffold_s = watch.seconds();
    const double e_prev = result.history.back().energy;
    const Problem p =
        make_problem(cut, rest, result.uv, scaffold, e_prev, options.scaffold_weight, false);
    const Eigen::MatrixXd D =
        newton_direction(p, st.assemble_s, st.solve_s, st.regularisation, st.gradient_norm);
    watch.reset();
    double em = 0, e = 0;
    const double t = line_search(p, D, options.armijo, 1e-12, st, e, em);
    st.line_search_s += watch.seconds();
    if (!(t > 0)) {
      result.newton_stop_reason = "line search";
      log::debug("param: Newton iteration ", k + 1, " stops: no acceptable step");
      break;
    }
    st.lambda = p.weight.size() > std::size_t(p.n_chart_faces) ? p.weight.back() : 0.0;
    st.scaffold_vertices = int(scaffold.V.rows());
    st.scaffold_faces = int(scaffold.F.rows());
    take_step(p, D, t, e, em, st);
    st.seconds = iteration.seconds();
    ++result.newton_iterations;
    report(st, scaffold);
    log::debug("param: Newton iteration ", k + 1, " energy ", st.energy, " step ", t, " gradient ",
               st.gradient_norm);
    if ((e_prev - em) / e_prev < options.newton_tolerance) {
      result.newton_stop_reason = "tolerance";
      break;
    }
  }
  result.seconds = total.seconds() - callback_s;
  const IterationStats& last = result.history.back();
  log::info("param: ", cut.num_charts, " chart(s), ", cut.num_faces(), " faces: energy ",
            result.history.front().energy, " -> ", last.energy, " in ", last.iteration,
            " iterations (", result.stop_reason,
            options.newton_iterations > 0 ? "; " + std::to_string(result.newton_iterations) +
                                                " Newton, " + result.newton_stop_reason
                                          : std::string(),
            "), ", result.seconds, " s");
  return result;
}

}  // namespace curvefem::meshing::param
