// SCAF with a tetrahedral scaffold: object fill, scaffold rebuild, SLIM proxy, flip-free search.
#include "meshing/param/scaf3d.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/param/slim_solve.hpp"
#include "meshing/param/symmetric_dirichlet.hpp"
#include "meshing/tetfill/tetfill.hpp"

namespace curvefem::meshing::param {

namespace {

using Mat43 = Eigen::Matrix<double, 4, 3>;
constexpr double k_inf = std::numeric_limits<double>::infinity();

// Gradients of the four barycentric functions of a tet whose edge matrix (x1−x0, x2−x0, x3−x0)
// is Dm: J = Xᵀ G for the 4 × 3 matrix X of its corners.
Mat43 gradient_operator(const Eigen::Matrix3d& Dm) {
  Mat43 B;
  B << -1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  return B * Dm.inverse();
}

Eigen::Matrix3d edge_matrix(const Eigen::MatrixXd& X, const Eigen::Vector4i& t) {
  Eigen::Matrix3d D;
  for (int k = 0; k < 3; ++k) D.col(k) = (X.row(t[k + 1]) - X.row(t[0])).transpose();
  return D;
}

// Rows of X: surface (ns), object Steiner points (no), box (nb), scaffold Steiner points.
struct Layout {
  int ns = 0, no = 0, nb = 0;
  int box_row(int i) const { return ns + no + i; }
  int scaffold_first() const { return ns + no + nb; }
};

struct Problem {
  Eigen::MatrixXd X;
  std::vector<int> dof;  // free index per row, −1 for the box
  int n_free = 0;
  int n_object = 0;  // tets [0, n_object) are the object's
  int slivers = 0;   // scaffold tets whose rest is the ε regular tet
  std::vector<Eigen::Vector4i> tet;
  std::vector<Mat43> G;
  std::vector<double> weight;  // V_t / V_M on the object, λ on the scaffold
  std::vector<PositionTarget> targets;
  double target_weight = 0;  // w / L² per target
  // Surface ARAP (Deform3dOptions::arap_weight): directed surface edges (i, j) by vertex i, their
  // rest vectors y_i − y_j, and w_A / Σ ‖y_i − y_j‖².
  const std::vector<std::vector<std::pair<int, Eigen::Vector3d>>>* arap_out = nullptr;
  double arap_scale = 0;

  // The rotation closest to vertex i's covariance Σ_j e0 (x_i − x_j)ᵀ at P (Sorkine and Alexa).
  Eigen::Matrix3d arap_rotation(int i, const Eigen::MatrixXd& P) const {
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    for (const auto& [j, e0] : (*arap_out)[std::size_t(i)]) S += e0 * (P.row(i) - P.row(j));
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(S, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d V = svd.matrixV();
    Eigen::Matrix3d R = V * svd.matrixU().transpose();
    if (R.determinant() < 0) {
      V.col(2) *= -1;
      R = V * svd.matrixU().transpose();
    }
    return R;
  }
  // The ARAP term at P (its rotations optimal at P) and, with D, its derivative along D.
  double arap_energy(const Eigen::MatrixXd& P, const Eigen::MatrixXd* D, double* slope) const {
    if (!arap_out || !(arap_scale > 0)) return 0;
    double e = 0, g = 0;
    for (int i = 0; i < int(arap_out->size()); ++i) {
      const Eigen::Matrix3d R = arap_rotation(i, P);
      for (const auto& [j, e0] : (*arap_out)[std::size_t(i)]) {
        const Eigen::Vector3d r = (P.row(i) - P.row(j)).transpose() - R * e0;
        e += r.squaredNorm();
        if (D) g += 2 * r.dot((D->row(i) - D->row(j)).transpose());
      }
    }
    if (slope) *slope = arap_scale * g;
    return arap_scale * e;
  }

  Eigen::Matrix3d jacobian(int t, const Eigen::MatrixXd& P) const {
    Mat43 Q;
    for (int k = 0; k < 4; ++k) Q.row(k) = P.row(tet[t][k]);
    return Q.transpose() * G[t];
  }
};

double evaluate(const Problem& p, const Eigen::MatrixXd& P, double& object) {
  double em = 0, es = 0, ec = 0;
  for (int t = 0; t < int(p.tet.size()); ++t) {
    const double d = symmetric_dirichlet_3d(p.jacobian(t, P));
    if (!std::isfinite(d)) {
      object = k_inf;
      return k_inf;
    }
    if (t < p.n_object)
      em += p.weight[t] * d;
    else
      es += p.weight[t] * (d - 6.0);
  }
  for (const PositionTarget& c : p.targets)
    ec += p.target_weight * (P.row(c.vertex).transpose() - c.target).squaredNorm();
  object = em;
  return em + es + ec + p.arap_energy(P, nullptr, nullptr);
}

double directional_derivative(const Problem& p, const Eigen::MatrixXd& P,
                              const Eigen::MatrixXd& D) {
  double g = 0;
  for (int t = 0; t < int(p.tet.size()); ++t)
    g += p.weight[t] *
         symmetric_dirichlet_gradient_3d(p.jacobian(t, P)).cwiseProduct(p.jacobian(t, D)).sum();
  for (const PositionTarget& c : p.targets)
    g += 2 * p.target_weight * (P.row(c.vertex).transpose() - c.target).dot(D.row(c.vertex));
  double arap = 0;
  p.arap_energy(P, &D, &arap);
  return g + arap;
}

// First root in (0, T] of the cubic c3 t³ + c2 t² + c1 t + c0 with c0 > 0 (T if none): the
// interval is cut at the derivative's roots into monotone pieces; the first piece whose right end
// is not positive holds the root, found by bisection.
double first_root(double c3, double c2, double c1, double c0, double T) {
  auto f = [&](double t) { return ((c3 * t + c2) * t + c1) * t + c0; };
  std::vector<double> cuts;
  // f' = 3 c3 t² + 2 c2 t + c1
  const double a = 3 * c3, b = 2 * c2, c = c1;
  if (a != 0) {
    const double disc = b * b - 4 * a * c;
    if (disc >= 0) {
      const double s = std::sqrt(disc);
      for (double r : {(-b - s) / (2 * a), (-b + s) / (2 * a)})
        if (r > 0 && r < T) cuts.push_back(r);
    }
  } else if (b != 0) {
    const double r = -c / b;
    if (r > 0 && r < T) cuts.push_back(r);
  }
  std::sort(cuts.begin(), cuts.end());
  cuts.push_back(T);
  double left = 0;
  for (double right : cuts) {
    if (f(right) <= 0) {
      double lo = left, hi = right;
      for (int k = 0; k < 80; ++k) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) > 0 ? lo : hi) = mid;
      }
      return lo;  // f(lo) > 0: still positive there
    }
    left = right;
  }
  return T;
}

// Largest t ≤ T such that every tet stays positive on [0, t).
double flip_free_bound(const Problem& p, const Eigen::MatrixXd& P, const Eigen::MatrixXd& D,
                       double T) {
  double t_max = T;
  for (const Eigen::Vector4i& t : p.tet) {
    const Eigen::Matrix3d E = edge_matrix(P, t), F = edge_matrix(D, t);
    auto det = [](const Eigen::Vector3d& x, const Eigen::Vector3d& y, const Eigen::Vector3d& z) {
      return x.dot(y.cross(z));
    };
    const Eigen::Vector3d e0 = E.col(0), e1 = E.col(1), e2 = E.col(2);
    const Eigen::Vector3d d0 = F.col(0), d1 = F.col(1), d2 = F.col(2);
    const double c0 = det(e0, e1, e2);
    const double c1 = det(d0, e1, e2) + det(e0, d1, e2) + det(e0, e1, d2);
    const double c2 = det(e0, d1, d2) + det(d0, e1, d2) + det(d0, d1, e2);
    const double c3 = det(d0, d1, d2);
    if (!(c0 > 0)) return 0;
    t_max = std::min(t_max, first_root(c3, c2, c1, c0, t_max));
  }
  return t_max;
}

Eigen::MatrixXd solve_proxy(const Problem& p, double& assemble_s, double& solve_s) {
  Stopwatch watch;
  const int n = 3 * p.n_free;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(p.tet.size() * 144 + p.targets.size() * 3);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  for (int t = 0; t < int(p.tet.size()); ++t) {
    Eigen::Matrix3d W, R;
    slim_weights_3d(p.jacobian(t, p.X), W, R);
    const Eigen::Matrix3d WR = W * R;
    // Unknown l = 4 i + k: coordinate i of corner k. (W J)_{jc} = Σ_{i,k} W_ji G_kc X_ki.
    Eigen::Matrix<double, 12, 12> M = Eigen::Matrix<double, 12, 12>::Zero();
    Eigen::Matrix<double, 12, 1> b = Eigen::Matrix<double, 12, 1>::Zero();
    for (int j = 0; j < 3; ++j)
      for (int c = 0; c < 3; ++c) {
        Eigen::Matrix<double, 12, 1> a;
        for (int i = 0; i < 3; ++i) a.segment<4>(4 * i) = W(j, i) * p.G[t].col(c);
        M.noalias() += p.weight[t] * a * a.transpose();
        b += p.weight[t] * WR(j, c) * a;
      }
    int row[12];
    for (int l = 0; l < 12; ++l) {
      const int v = p.tet[t][l % 4];
      row[l] = p.dof[v] >= 0 ? 3 * p.dof[v] + l / 4 : -1;
    }
    for (int l = 0; l < 12; ++l) {
      if (row[l] < 0) continue;
      rhs[row[l]] += b[l];
      for (int m = 0; m < 12; ++m) {
        if (row[m] >= 0)
          trip.emplace_back(row[l], row[m], M(l, m));
        else
          rhs[row[l]] -= M(l, m) * p.X(p.tet[t][m % 4], m / 4);
      }
    }
  }
  for (const PositionTarget& c : p.targets)
    for (int i = 0; i < 3; ++i) {
      const int r = 3 * p.dof[c.vertex] + i;
      trip.emplace_back(r, r, p.target_weight);
      rhs[r] += p.target_weight * c.target[i];
    }
  // ARAP's global step with the rotations of x_k: s ‖(x_i − x_j) − R_i e0‖² per directed edge
  // (surface vertices are never fixed).
  if (p.arap_out && p.arap_scale > 0)
    for (int i = 0; i < int(p.arap_out->size()); ++i) {
      const Eigen::Matrix3d R = p.arap_rotation(i, p.X);
      for (const auto& [j, e0] : (*p.arap_out)[std::size_t(i)]) {
        const Eigen::Vector3d r = R * e0;
        const double s = p.arap_scale;
        for (int k = 0; k < 3; ++k) {
          const int a = 3 * p.dof[std::size_t(i)] + k, b = 3 * p.dof[std::size_t(j)] + k;
          trip.emplace_back(a, a, s);
          trip.emplace_back(b, b, s);
          trip.emplace_back(a, b, -s);
          trip.emplace_back(b, a, -s);
          rhs[a] += s * r[k];
          rhs[b] -= s * r[k];
        }
      }
    }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(trip.begin(), trip.end());
  assemble_s += watch.seconds();
  watch.reset();
  Eigen::VectorXd x0(n);
  for (int v = 0; v < int(p.dof.size()); ++v)
    if (p.dof[v] >= 0) x0.segment<3>(3 * p.dof[v]) = p.X.row(v).transpose();
  double regularisation = 0;
  const Eigen::VectorXd x = solve_slim_system(A, rhs, x0, regularisation, "scaf3d");
  solve_s += watch.seconds();
  Eigen::MatrixXd target = p.X;
  for (int v = 0; v < int(p.dof.size()); ++v)
    if (p.dof[v] >= 0) target.row(v) = x.segment<3>(3 * p.dof[v]).transpose();
  return target;
}

Eigen::MatrixXi reversed(const Eigen::MatrixXi& F) {
  Eigen::MatrixXi R = F;
  R.col(1) = F.col(2);
  R.col(2) = F.col(1);
  return R;
}

// The scaffold's own numbering: surface, box, Steiner points (fill_interior keeps the input rows
// first). Global rows from local ones.
struct Scaffold {
  Eigen::MatrixXi T;        // global rows
  Eigen::MatrixXd steiner;  // its Steiner points
  bool rebuilt = false;
};

Scaffold build_scaffold(const Eigen::MatrixXd& surface_V, const Eigen::MatrixXi& surface_F,
                        const SurfaceMesh& box, const Layout& L) {
  const int ns = L.ns, nb = L.nb;
  Eigen::MatrixXd V(ns + nb, 3);
  V.topRows(ns) = surface_V;
  V.bottomRows(nb) = box.V;
  Eigen::MatrixXi F(surface_F.rows() + box.F.rows(), 3);
  F.topRows(surface_F.rows()) = reversed(surface_F);
  F.bottomRows(box.F.rows()) = box.F.array() + ns;
  tetfill::TetFillOptions fill;
  fill.optimize = true;
  fill.quiet = true;
  const tetfill::TetFillResult r = tetfill::fill_interior(V, F, fill);
  Scaffold s;
  s.rebuilt = true;
  s.steiner = r.V.bottomRows(r.V.rows() - (ns + nb));
  s.T.resize(r.T.rows(), 4);
  for (Eigen::Index t = 0; t < r.T.rows(); ++t)
    for (int k = 0; k < 4; ++k) {
      const int v = r.T(t, k);
      s.T(t, k) = v < ns ? v : v < ns + nb ? L.box_row(v - ns) : L.scaffold_first() + v - ns - nb;
    }
  return s;
}

struct SingularRange {
  double lo = k_inf, hi = 0;
};

}  // namespace

Deform3dResult scaf3d_deform(const SurfaceMesh& surface, const std::vector<PositionTarget>& targets,
                             const Deform3dOptions& options) {
  Stopwatch total;
  double callback_s = 0;
  const int ns = surface.num_vertices();
  for (const PositionTarget& c : targets) {
    if (c.vertex < 0 || c.vertex >= ns)
      throw InputError("scaf3d: target vertex " + std::to_string(c.vertex) + " is not a vertex (" +
                       std::to_string(ns) + " vertices)");
    if (!c.target.allFinite())
      throw InputError("scaf3d: the target of vertex " + std::to_string(c.vertex) +
                       " is not finite");
  }
  if (!(options.grow > 0) || !(options.box_scale > 1))
    throw InputError("scaf3d: grow must be > 0 and box_scale > 1");

  // The object: the solid inside the surface, its rest shape the input scaled by `grow`.
  tetfill::TetFillOptions object_fill;
  object_fill.quiet = true;
  const tetfill::TetFillResult object = tetfill::fill_interior(surface.V, surface.F, object_fill);
  Layout L;
  L.ns = ns;
  L.no = int(object.V.rows()) - ns;
  // The box holds the surface and the targets (a target outside it could not be reached).
  Eigen::Vector3d lo = surface.V.colwise().minCoeff(), hi = surface.V.colwise().maxCoeff();
  for (const PositionTarget& c : targets) {
    lo = lo.cwiseMin(c.target);
    hi = hi.cwiseMax(c.target);
  }
  // Padded by the same length on every side, (box_scale − 1) / 2 × the longest extent, so that
  // a thin object (a plate) still gets a scaffold of well-shaped tets across its thin direction.
  const double pad = 0.5 * (options.box_scale - 1) * (hi - lo).maxCoeff();
  const Eigen::Vector3d centre = 0.5 * (lo + hi),
                        half = 0.5 * (hi - lo) + Eigen::Vector3d::Constant(pad);
  const SurfaceMesh box =
      make_box(centre - half, centre + half, std::max(1, options.box_divisions));
  L.nb = int(box.V.rows());
  const double diag = (2 * half).norm();
  // Surface ARAP's directed edges and rest vectors (Deform3dOptions::arap_weight).
  std::vector<std::vector<std::pair<int, Eigen::Vector3d>>> arap_out;
  double arap_scale = 0;
  if (!(options.arap_weight >= 0) || !std::isfinite(options.arap_weight))
    throw InputError("scaf3d: the ARAP weight must be finite and >= 0");
  if (options.arap_weight > 0) {
    const Eigen::MatrixXd rest = options.arap_rest.size() > 0
                                     ? options.arap_rest
                                     : Eigen::MatrixXd(options.grow * surface.V);
    if (rest.rows() != ns || rest.cols() != 3 || !rest.allFinite())
      throw InputError("scaf3d: the ARAP rest positions need one finite row (x, y, z) per vertex");
    arap_out.resize(std::size_t(ns));
    std::vector<std::vector<int>> seen(static_cast<std::size_t>(ns));
    double total = 0;
    for (Eigen::Index f = 0; f < surface.F.rows(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = surface.F(f, k), b = surface.F(f, (k + 1) % 3);
        for (const auto& [i, j] : {std::pair{a, b}, std::pair{b, a}}) {
          auto& s = seen[std::size_t(i)];
          if (std::find(s.begin(), s.end(), j) != s.end()) continue;
          s.push_back(j);
          const Eigen::Vector3d e0 = (rest.row(i) - rest.row(j)).transpose();
          arap_out[std::size_t(i)].emplace_back(j, e0);
          total += e0.squaredNorm();
        }
      }
    if (!(total > 0)) throw InputError("scaf3d: the ARAP rest shape has no edge length");
    arap_scale = options.arap_weight / total;
  }

  std::vector<Mat43> object_G(std::size_t(object.T.rows()));
  std::vector<double> object_w(std::size_t(object.T.rows()));
  double object_volume = 0;
  for (Eigen::Index t = 0; t < object.T.rows(); ++t) {
    const Eigen::Vector4i tt = object.T.row(t).transpose();
    const Eigen::Matrix3d Dm = options.grow * edge_matrix(object.V, tt);
    object_G[std::size_t(t)] = gradient_operator(Dm);
    object_w[std::size_t(t)] = Dm.determinant() / 6;
    object_volume += object_w[std::size_t(t)];
  }
  for (double& w : object_w) w /= object_volume;

  Deform3dResult result;
  Eigen::MatrixXd X(L.scaffold_first(), 3);
  X.topRows(ns + L.no) = object.V;
  X.middleRows(L.box_row(0), L.nb) = box.V;
  Stopwatch watch;
  Scaffold scaffold = build_scaffold(surface.V, surface.F, box, L);
  double first_scaffold_s = watch.seconds();
  {
    Eigen::MatrixXd grown(X.rows() + scaffold.steiner.rows(), 3);
    grown << X, scaffold.steiner;
    X = grown;
  }

  auto make_problem = [&](double e_object, bool replace_slivers) {
    Problem p;
    p.X = X;
    p.dof.assign(std::size_t(X.rows()), -1);
    for (int v = 0; v < int(X.rows()); ++v)
      if (v < L.box_row(0) || v >= L.scaffold_first()) p.dof[std::size_t(v)] = p.n_free++;
    p.n_object = int(object.T.rows());
    for (Eigen::Index t = 0; t < object.T.rows(); ++t) {
      p.tet.push_back(object.T.row(t).transpose());
      p.G.push_back(object_G[std::size_t(t)]);
      p.weight.push_back(object_w[std::size_t(t)]);
    }
    const double lambda =
        options.scaffold_weight * e_object / std::max<Eigen::Index>(1, scaffold.T.rows());
    // ε = l³ / 16, l = the surface's shortest edge now (Deform3dOptions::replace_slivers).
    double eps = 0;
    Mat43 G_eps;
    if (replace_slivers) {
      double l = HUGE_VAL;
      for (Eigen::Index f = 0; f < surface.F.rows(); ++f)
        for (int k = 0; k < 3; ++k)
          l = std::min(l, (X.row(surface.F(f, k)) - X.row(surface.F(f, (k + 1) % 3))).norm());
      eps = l * l * l / 16;
      // The regular tet of volume ε: edge a with a³ / (6√2) = ε.
      const double a = std::cbrt(6 * std::sqrt(2.0) * eps);
      Eigen::Matrix3d regular;
      regular.col(0) << a, 0, 0;
      regular.col(1) << a / 2, a * std::sqrt(3.0) / 2, 0;
      regular.col(2) << a / 2, a * std::sqrt(3.0) / 6, a * std::sqrt(2.0 / 3.0);
      G_eps = gradient_operator(regular);
    }
    for (Eigen::Index t = 0; t < scaffold.T.rows(); ++t) {
      const Eigen::Vector4i tt = scaffold.T.row(t).transpose();
      const Eigen::Matrix3d Dm = edge_matrix(X, tt);
      const bool sliver = Dm.determinant() / 6 < eps;
      p.slivers += sliver;
      p.tet.push_back(tt);
      p.G.push_back(sliver ? G_eps : gradient_operator(Dm));
      p.weight.push_back(lambda);
    }
    p.targets = targets;
    p.target_weight = options.target_weight / (diag * diag);
    if (arap_scale > 0) {
      p.arap_out = &arap_out;
      p.arap_scale = arap_scale;
    }
    return p;
  };
  // The worst scaffold tet shape at P: min of 6√2 V / ℓ_rms³ (0 without scaffold tets).
  auto scaffold_quality = [](const Problem& p, const Eigen::MatrixXd& P) {
    double worst = k_inf;
    for (int t = p.n_object; t < int(p.tet.size()); ++t) {
      const Eigen::Vector4i& c = p.tet[std::size_t(t)];
      double l2 = 0;
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) l2 += (P.row(c[a]) - P.row(c[b])).squaredNorm();
      const double rms = std::sqrt(l2 / 6);
      worst = std::min(worst, std::sqrt(2.0) * edge_matrix(P, c).determinant() / (rms * rms * rms));
    }
    return worst < k_inf ? worst : 0.0;
  };
  auto measure = [&](const Problem& p, const Eigen::MatrixXd& P, Deform3dIteration& st) {
    SingularRange r;
    double vmin = k_inf;
    for (int t = 0; t < int(p.tet.size()); ++t) {
      if (t < p.n_object) {
        const Eigen::Matrix3d J = p.jacobian(t, P);
        Eigen::Matrix3d W, R;
        Eigen::Vector3d s;
        if (J.determinant() > 0) {
          slim_weights_3d(J, W, R, &s);
          r.lo = std::min(r.lo, s[2]);
          r.hi = std::max(r.hi, s[0]);
        } else {
          r.lo = 0;
        }
      }
      vmin = std::min(vmin, edge_matrix(P, p.tet[std::size_t(t)]).determinant() / 6);
    }
    st.min_singular = r.lo;
    st.max_singular = r.hi;
    st.min_volume_rel = vmin / (diag * diag * diag);
    st.target_error = 0;
    for (const PositionTarget& c : targets)
      st.target_error =
          std::max(st.target_error, (P.row(c.vertex).transpose() - c.target).norm() / diag);
    st.scaffold_tets = int(scaffold.T.rows());
    st.scaffold_min_quality = scaffold_quality(p, P);
    st.arap = arap_scale > 0 ? p.arap_energy(P, nullptr, nullptr) / options.arap_weight : 0.0;
  };
  auto report = [&](const Deform3dIteration& st) {
    result.history.push_back(st);
    if (options.on_iteration) {
      Stopwatch cb;
      options.on_iteration(st, X.topRows(ns));
      callback_s += cb.seconds();
    }
  };

  {
    Deform3dIteration st0;
    Problem p = make_problem(6.0, false);
    double em = 0;
    st0.objective = evaluate(p, X, em);
    st0.energy = em;
    st0.scaffold_s = first_scaffold_s;
    st0.scaffold_rebuilt = true;
    measure(p, X, st0);
    st0.scaffold_reference_quality = st0.scaffold_min_quality;
    if (!std::isfinite(st0.objective))
      throw MeshingError("scaf3d: the initial object or scaffold has a non-positive tet");
    report(st0);
  }
  result.stop_reason = "iterations";
  // The worst scaffold tet shape of the last rebuild (Deform3dOptions::rebuild_quality).
  double rebuilt_quality = result.history.back().scaffold_min_quality;
  for (int it = 1; it <= options.max_iterations; ++it) {
    Stopwatch iteration;
    Deform3dIteration st;
    st.iteration = it;
    if (it > 1 && options.rebuild_quality > 0 &&
        result.history.back().scaffold_min_quality >= options.rebuild_quality * rebuilt_quality) {
      ++result.scaffold_kept;  // the moved scaffold is still about as good as a rebuild: kept
    } else if (it > 1) {
      watch.reset();
      try {
        Scaffold fresh = build_scaffold(X.topRows(ns), surface.F, box, L);
        Eigen::MatrixXd kept = X.topRows(L.scaffold_first());
        X.resize(kept.rows() + fresh.steiner.rows(), 3);
        X << kept, fresh.steiner;
        scaffold = std::move(fresh);
        st.scaffold_rebuilt = true;
        rebuilt_quality = -1;  // measured after this iteration's make_problem, below
      } catch (const MeshingError& e) {
        // The moved scaffold is still a positive tiling: keep it.
        ++result.scaffold_failures;
        log::debug("scaf3d: iteration ", it, ": scaffold not rebuilt (", e.what(), ")");
      }
      st.scaffold_s = watch.seconds();
    } else {
      st.scaffold_rebuilt = true;
    }
    const double e_prev = result.history.back().objective;
    // With slivers' rest the ε regular tet, the scaffold pushes back and the direction may trade
    // E_M for it: the step must lower E (Armijo) without raising E_M; when no step does, the
    // iteration is redone with every rest its current shape (thesis §3.2.2, as in 2-D).
    const Problem standard = make_problem(result.history.back().energy, false);
    if (rebuilt_quality < 0) rebuilt_quality = scaffold_quality(standard, standard.X);
    st.scaffold_reference_quality = rebuilt_quality;
    std::optional<Problem> with_slivers;
    if (options.replace_slivers) {
      with_slivers.emplace(make_problem(result.history.back().energy, true));
      st.slivers = with_slivers->slivers;
      if (st.slivers == 0) with_slivers.reset();  // the same problem
    }
    const Problem* p = nullptr;
    Eigen::MatrixXd D;
    double em = 0, e = 0, t = 0;
    double sliver_decrease = 0;  // of the ε problem's E over a step taken with it, relative
    bool accepted = false;
    for (const Problem* attempt :
         std::array<const Problem*, 2>{with_slivers ? &*with_slivers : nullptr, &standard}) {
      if (!attempt) continue;
      p = attempt;
      const bool guard = attempt != &standard;  // E_M may not rise
      const Eigen::MatrixXd target = solve_proxy(*p, st.assemble_s, st.solve_s);
      watch.reset();
      D = target - p->X;
      double em0 = 0;
      const double e0 = evaluate(*p, p->X, em0);
      const double slope = directional_derivative(*p, p->X, D);
      st.max_step = std::min(1.0, 0.8 * flip_free_bound(*p, p->X, D, 1.25));
      t = st.max_step;
      if (slope < 0 && t > 0)
        for (int k = 0; k < 60 && t >= 1e-12 * st.max_step; ++k, t *= 0.5) {
          e = evaluate(*p, p->X + t * D, em);
          if (std::isfinite(e) && e <= e0 + options.armijo * t * slope && (!guard || em <= em0)) {
            accepted = true;
            break;
          }
          ++st.backtracks;
        }
      st.line_search_s += watch.seconds();
      if (accepted) {
        st.slivers_kept = guard;
        if (guard) {
          sliver_decrease = (e0 - e) / std::abs(e0);
          e = evaluate(standard, p->X + t * D, em);  // E as the iterations compare it
        }
        break;
      }
    }
    if (!accepted) {
      result.stop_reason = "line search";
      log::debug("scaf3d: iteration ", it, " stops: no acceptable step");
      break;
    }
    X = p->X + t * D;
    st.step = t;
    st.energy = em;
    st.objective = e;
    measure(standard, X, st);
    st.seconds = iteration.seconds() + (it == 1 ? first_scaffold_s : 0.0);
    report(st);
    log::debug("scaf3d: iteration ", it, " E ", e, " E_M ", em, " step ", t, " (max ", st.max_step,
               "), target error ", st.target_error, ", ", st.seconds, " s");
    // A step taken with sliver rests may raise E (the scaffold pushed two sheets apart): it is
    // judged by its own problem's decrease.
    if ((st.slivers_kept ? sliver_decrease : (e_prev - e) / std::abs(e_prev)) < options.tolerance) {
      result.stop_reason = "tolerance";
      break;
    }
  }
  result.V = X.topRows(ns);
  result.X = X;
  result.object_tets = object.T;
  result.scaffold_tets = scaffold.T;
  result.box_faces = box.F.array() + L.box_row(0);
  result.seconds = total.seconds() - callback_s;
  const Deform3dIteration& last = result.history.back();
  log::info("scaf3d: ", surface.num_faces(), " faces, ", object.T.rows(), " object tets: E ",
            result.history.front().objective, " -> ", last.objective, " (E_M ", last.energy,
            ", target error ", last.target_error, ") in ", last.iteration, " iterations (",
            result.stop_reason, "), ", result.seconds, " s");
  return result;
}

Deform3dCheck verify_scaf3d(const SurfaceMesh& input, const Deform3dResult& r) {
  Deform3dCheck check;
  const int ns = input.num_vertices();
  CF_VERIFY(r.X.rows() >= ns && r.V.rows() == ns, "verify_scaf3d: result sizes");
  CF_VERIFY(r.box_faces.size() > 0, "verify_scaf3d: no box");
  // Rows: surface [0, ns), object Steiner points [ns, box_first), box [box_first, box_last),
  // scaffold Steiner points after.
  const int box_first = r.box_faces.minCoeff(), box_last = r.box_faces.maxCoeff() + 1;
  const int no = box_first - ns;
  tetfill::TetFillResult object;
  object.V = r.X.topRows(ns + no);
  object.T = r.object_tets;
  object.boundary_vertices = ns;
  const tetfill::TetFillVerification vo = tetfill::verify_tetfill(r.V, input.F, object);
  // Scaffold: its own numbering (surface, box, Steiner), boundary = reversed surface + box.
  const int nb = box_last - box_first;
  Eigen::MatrixXd Vin(ns + nb, 3);
  Vin.topRows(ns) = r.V;
  Vin.bottomRows(nb) = r.X.middleRows(box_first, nb);
  Eigen::MatrixXi Fin(input.F.rows() + r.box_faces.rows(), 3);
  Fin.topRows(input.F.rows()) = reversed(input.F);
  Fin.bottomRows(r.box_faces.rows()) = r.box_faces.array() - box_first + ns;
  tetfill::TetFillResult scaffold;
  scaffold.V.resize(ns + nb + (r.X.rows() - box_last), 3);
  scaffold.V << Vin, r.X.bottomRows(r.X.rows() - box_last);
  scaffold.boundary_vertices = ns + nb;
  scaffold.T.resize(r.scaffold_tets.rows(), 4);
  for (Eigen::Index t = 0; t < r.scaffold_tets.rows(); ++t)
    for (int k = 0; k < 4; ++k) {
      const int g = r.scaffold_tets(t, k);
      scaffold.T(t, k) = g < ns ? g : g < box_last ? g - box_first + ns : g - box_last + ns + nb;
    }
  const tetfill::TetFillVerification vs = tetfill::verify_tetfill(Vin, Fin, scaffold);
  check.non_positive_tets = vo.non_positive_tets + vs.non_positive_tets;
  check.boundary_mismatches = vo.missing_boundary_faces + vo.extra_boundary_faces +
                              vo.bad_interior_faces + vs.missing_boundary_faces +
                              vs.extra_boundary_faces + vs.bad_interior_faces;
  const Eigen::Vector3d lo = Vin.bottomRows(nb).colwise().minCoeff(),
                        hi = Vin.bottomRows(nb).colwise().maxCoeff();
  const double box_volume = (hi - lo).prod();
  check.volume_error_rel = std::abs(vo.tet_volume + vs.tet_volume - box_volume) / box_volume;
  return check;
}

std::vector<PositionTarget> read_target_file(const std::string& path, int num_vertices) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open target file " + path);
  std::vector<PositionTarget> targets;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream s(line);
    std::string first;
    if (!(s >> first)) continue;
    ErrorContext ctx;
    ctx.file = path;
    ctx.line = number;
    PositionTarget c;
    std::istringstream vs(first);
    std::string rest;
    if (!(vs >> c.vertex) || (vs >> rest))
      throw InputError("target file: '" + first + "' is not a vertex id", ctx);
    if (!(s >> c.target.x() >> c.target.y() >> c.target.z()) || (s >> rest))
      throw InputError("target file: expected 'vertex x y z'", ctx);
    if (c.vertex < 0 || c.vertex >= num_vertices)
      throw InputError("target file: vertex " + std::to_string(c.vertex) + " is not in [0, " +
                           std::to_string(num_vertices) + ")",
                       ctx);
    if (!c.target.allFinite()) throw InputError("target file: non-finite coordinate", ctx);
    targets.push_back(c);
  }
  return targets;
}

}  // namespace curvefem::meshing::param
