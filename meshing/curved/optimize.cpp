#include "meshing/curved/optimize.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>

#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/curved/jacobian_certificate.hpp"

namespace curvefem::meshing::curved {
namespace {

constexpr double k_inf = std::numeric_limits<double>::infinity();

// Reference quantities shared by every cell of one order.
struct Reference {
  int k = 1, nn = 4;
  const std::vector<std::array<int, 4>>* lattice = nullptr;
  std::vector<Eigen::MatrixXd> grads;  // per sample point, nn × 3 shape gradients
  std::array<int, 4> corner_row{};     // lattice row of each vertex
  Eigen::Matrix3d Winv;                // right reference tet → regular tet, inverted
  std::array<Eigen::Vector3d, 4> grad_lambda;

  explicit Reference(int order) : k(order) {
    lattice = &lagrange_lattice(CellKind::tetrahedron, k);
    nn = int(lattice->size());
    for (int n = 0; n < nn; ++n)
      for (int j = 0; j < 4; ++j)
        if ((*lattice)[n][j] == k) corner_row[j] = n;
    if (k == 1) {
      grads.push_back(
          lagrange_shape_gradients(CellKind::tetrahedron, 1, Eigen::Vector3d::Constant(0.25)));
    } else {
      // The order-k lattice. (Searching on the order-2 lattice only made k = 4 visits 3.5 times
      // cheaper but let the worst sampled scaled Jacobian of bunny drop from 2e-3 to 1e-4.)
      const Eigen::MatrixXd xi = lagrange_reference_nodes(CellKind::tetrahedron, k);
      for (int n = 0; n < int(xi.rows()); ++n)
        grads.push_back(
            lagrange_shape_gradients(CellKind::tetrahedron, k, Eigen::Vector3d(xi.row(n))));
    }
    Eigen::Matrix3d W;
    W.col(0) = Eigen::Vector3d(1, 0, 0);
    W.col(1) = Eigen::Vector3d(0.5, std::sqrt(3.0) / 2, 0);
    W.col(2) = Eigen::Vector3d(0.5, std::sqrt(3.0) / 6, std::sqrt(2.0 / 3.0));
    Winv = W.inverse();
    grad_lambda[0] = Eigen::Vector3d(-1, -1, -1);
    for (int j = 1; j < 4; ++j) grad_lambda[j] = Eigen::Vector3d::Unit(j - 1);
  }
};

// Conformal AMIPS of J (already against the regular tet) and, optionally, its gradient dE/dJ.
double amips(const Eigen::Matrix3d& J, Eigen::Matrix3d* grad) {
  const double det = J.determinant();
  if (!(det > 0)) return k_inf;
  const double d23 = std::cbrt(det * det);
  const double e = J.squaredNorm() / (3 * d23);
  if (grad) *grad = (2.0 / (3 * d23)) * J - (2.0 / 3.0) * e * J.inverse().transpose();
  return e;
}

// One star cell during a vertex visit: the Jacobians at the samples with the vertex at its
// current position, and the vertex's local index.
struct StarCell {
  int cell, local;
  std::vector<Eigen::Matrix3d> J0;  // against the regular tet
};

struct StarEnergy {
  double sum = 0, max = 0;
};

StarEnergy star_energy(const Reference& ref, const std::vector<StarCell>& star,
                       const Eigen::Vector3d& delta, Eigen::Vector3d* gradient) {
  StarEnergy out;
  if (gradient) gradient->setZero();
  for (const StarCell& s : star) {
    // J(Δ) = J0 + Δ (∇λ)ᵀ W⁻¹.
    const Eigen::RowVector3d g = ref.grad_lambda[s.local].transpose() * ref.Winv;
    const Eigen::Matrix3d dJ = delta * g;
    double e = 0;
    Eigen::Vector3d grad_cell = Eigen::Vector3d::Zero();
    for (const Eigen::Matrix3d& J0 : s.J0) {
      Eigen::Matrix3d dE;
      const double v = amips(J0 + dJ, gradient ? &dE : nullptr);
      if (v == k_inf) return {k_inf, k_inf};
      e += v;
      if (gradient) grad_cell += dE * g.transpose();
    }
    const double inv = 1.0 / double(s.J0.size());
    e *= inv;
    out.sum += e;
    out.max = std::max(out.max, e);
    if (gradient) *gradient += inv * grad_cell;
  }
  return out;
}

Eigen::MatrixXd cell_nodes(const LagrangeMesh& mesh, int c) {
  Eigen::MatrixXd X(mesh.cells.cols(), 3);
  for (Eigen::Index n = 0; n < mesh.cells.cols(); ++n) X.row(n) = mesh.nodes.row(mesh.cells(c, n));
  return X;
}

// Energy over the order-k lattice.
double energy_of(const Reference& ref, const Eigen::MatrixXd& X) {
  double e = 0;
  for (const Eigen::MatrixXd& G : ref.grads) {
    const Eigen::Matrix3d J = X.transpose() * G;
    const double v = amips(J * ref.Winv, nullptr);
    if (v == k_inf) return k_inf;
    e += v;
  }
  return e / double(ref.grads.size());
}

}  // namespace

double cell_energy(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes) {
  const Reference ref(order);
  CF_VERIFY(nodes.rows() == ref.nn && nodes.cols() == 3, "cell_energy: wrong node matrix");
  return energy_of(ref, nodes);
}

OptimizeStats optimize_vertices(LagrangeMesh& mesh, const OptimizeOptions& options,
                                const ProgressFn& progress, const std::vector<char>* frozen) {
  Stopwatch watch;
  OptimizeStats stats;
  if (mesh.kind != CellKind::tetrahedron)
    throw InputError("optimize_vertices: needs a tetrahedral mesh");
  const Reference ref(mesh.order);
  const int nc = mesh.num_cells(), k = ref.k;

  // Boundary corners: corners of faces used by one cell only.
  std::map<std::array<int, 3>, int> face_count;
  auto corner = [&](int c, int j) { return mesh.cells(c, ref.corner_row[j]); };
  for (int c = 0; c < nc; ++c)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> f;
      int m = 0;
      for (int j = 0; j < 4; ++j)
        if (j != skip) f[m++] = corner(c, j);
      std::sort(f.begin(), f.end());
      ++face_count[f];
    }
  std::vector<char> fixed(mesh.num_nodes(), 0), is_corner(mesh.num_nodes(), 0);
  for (const auto& [f, count] : face_count)
    if (count == 1)
      for (int v : f) fixed[v] = 1;
  if (frozen) {
    CF_VERIFY(int(frozen->size()) == mesh.num_nodes(), "optimize_vertices: frozen has wrong size");
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if ((*frozen)[std::size_t(v)]) fixed[v] = 1;
  }
  std::vector<std::vector<std::pair<int, int>>> star(mesh.num_nodes());
  for (int c = 0; c < nc; ++c)
    for (int j = 0; j < 4; ++j) {
      is_corner[corner(c, j)] = 1;
      star[corner(c, j)].emplace_back(c, j);
    }

  std::vector<double> energy(nc);
  for (int c = 0; c < nc; ++c) energy[c] = energy_of(ref, cell_nodes(mesh, c));
  auto summarize = [&](double& mean, double& max) {
    mean = max = 0;
    for (double e : energy) {
      mean += e / std::max(nc, 1);
      max = std::max(max, e);
    }
  };
  summarize(stats.mean_energy_before, stats.max_energy_before);

  std::vector<int> active;
  for (int v = 0; v < mesh.num_nodes(); ++v)
    if (is_corner[v] && !fixed[v]) active.push_back(v);
  stats.movable_vertices = int(active.size());

  for (int sweep = 0; sweep < options.sweeps && !active.empty(); ++sweep) {
    ++stats.sweeps;
    // Worst stars first.
    std::vector<std::pair<double, int>> order;
    for (int v : active) {
      double worst = 0;
      for (const auto& [c, j] : star[v]) worst = std::max(worst, energy[c]);
      order.emplace_back(-worst, v);
    }
    std::sort(order.begin(), order.end());
    // Vertices that share no tet have disjoint stars (a node moved by v lies only in tets
    // holding v), so a colour class of the vertex graph is visited in parallel with the same
    // result as serially, for any thread count.
    std::vector<int> colour(mesh.num_nodes(), -1);
    std::vector<std::vector<int>> classes;
    for (const auto& [neg, v] : order) {
      std::vector<char> used(classes.size() + 1, 0);
      for (const auto& [c, j] : star[v])
        for (int i = 0; i < 4; ++i) {
          const int w = corner(c, i);
          if (w != v && colour[w] >= 0) used[colour[w]] = 1;
        }
      int col = 0;
      while (used[col]) ++col;
      colour[v] = col;
      if (col == int(classes.size())) classes.emplace_back();
      classes[col].push_back(v);
    }
    std::vector<char> moved_vertex(mesh.num_nodes(), 0);
    std::atomic<long long> visits{0}, moves{0}, rejected{0};
    auto visit_vertex = [&](int v) {
      ++visits;
      std::vector<StarCell> cells;
      double length = 0;
      int edges = 0;
      for (const auto& [c, j] : star[v]) {
        StarCell s{c, j, {}};
        const Eigen::MatrixXd X = cell_nodes(mesh, c);
        for (const Eigen::MatrixXd& G : ref.grads) s.J0.push_back((X.transpose() * G) * ref.Winv);
        cells.push_back(std::move(s));
        for (int i = 0; i < 4; ++i)
          if (i != j) {
            length += (mesh.nodes.row(corner(c, i)) - mesh.nodes.row(v)).norm();
            ++edges;
          }
      }
      length /= std::max(edges, 1);
      const StarEnergy start = star_energy(ref, cells, Eigen::Vector3d::Zero(), nullptr);
      if (start.sum == k_inf) return;  // an uncertifiable star: leave it alone
      Eigen::Vector3d delta = Eigen::Vector3d::Zero();
      StarEnergy current = start;
      for (int it = 0; it < options.iterations; ++it) {
        Eigen::Vector3d g;
        star_energy(ref, cells, delta, &g);
        if (!(g.norm() > 0)) break;
        // Newton direction from a finite-difference Hessian of the analytic gradient, else
        // steepest descent.
        const double h = 1e-6 * length;
        Eigen::Matrix3d H;
        for (int i = 0; i < 3; ++i) {
          Eigen::Vector3d gi;
          star_energy(ref, cells, delta + h * Eigen::Vector3d::Unit(i), &gi);
          H.col(i) = (gi - g) / h;
        }
        H = 0.5 * (H + H.transpose()).eval();
        Eigen::Vector3d dir;
        Eigen::LLT<Eigen::Matrix3d> llt(H);
        if (llt.info() == Eigen::Success && H.allFinite())
          dir = -llt.solve(g);
        else
          dir = -g;
        if (!dir.allFinite() || dir.dot(g) >= 0) dir = -g;
        const double cap = 0.5 * length;  // never jump across the star
        if (dir.norm() > cap) dir *= cap / dir.norm();
        bool stepped = false;
        for (double t = 1.0; t > 1e-4; t *= 0.5) {
          const StarEnergy trial = star_energy(ref, cells, delta + t * dir, nullptr);
          if (trial.sum < current.sum && trial.max <= start.max) {
            delta += t * dir;
            stepped = current.sum - trial.sum > options.tolerance * current.sum;
            current = trial;
            break;
          }
        }
        if (!stepped) break;
      }
      // Moves that gain less than the tolerance are not worth a certificate (the certificate of
      // the star costs far more than the search), and they keep the sweeps going.
      if (!(start.sum - current.sum > options.tolerance * start.sum) || delta.isZero(0)) return;

      std::vector<std::pair<int, double>> moved;  // node, barycentric weight of v
      for (const auto& [c, j] : star[v])
        for (int n = 0; n < ref.nn; ++n)
          if ((*ref.lattice)[n][j] > 0) moved.emplace_back(mesh.cells(c, n), (*ref.lattice)[n][j]);
      std::sort(moved.begin(), moved.end());
      moved.erase(std::unique(moved.begin(), moved.end(),
                              [](const auto& a, const auto& b) { return a.first == b.first; }),
                  moved.end());
      // Apply, certify every star cell, restore the saved rows exactly on failure (halving the
      // move a few times while it still improves the search energy).
      std::vector<Eigen::RowVector3d> saved;
      for (const auto& [node, a] : moved) saved.push_back(mesh.nodes.row(node));
      auto restore = [&] {
        for (std::size_t i = 0; i < moved.size(); ++i) mesh.nodes.row(moved[i].first) = saved[i];
      };
      bool accepted = false;
      for (int attempt = 0; attempt < 4; ++attempt) {
        for (std::size_t i = 0; i < moved.size(); ++i)
          mesh.nodes.row(moved[i].first) = saved[i] + (moved[i].second / k) * delta.transpose();
        accepted = true;
        for (const auto& [c, j] : star[v])
          if (certify_tet_jacobian(k, cell_nodes(mesh, c)).verdict != JacobianVerdict::positive) {
            accepted = false;
            break;
          }
        if (accepted) break;
        ++rejected;
        restore();
        delta *= 0.5;
        const StarEnergy half = star_energy(ref, cells, delta, nullptr);
        if (!(start.sum - half.sum > options.tolerance * start.sum && half.max <= start.max)) break;
      }
      if (!accepted) return;
      ++moves;
      moved_vertex[v] = 1;
      for (const auto& [c, j] : star[v]) energy[c] = energy_of(ref, cell_nodes(mesh, c));
    };
    std::size_t done = 0;
    for (const auto& cls : classes) {
      tbb::parallel_for(std::size_t(0), cls.size(), [&](std::size_t i) { visit_vertex(cls[i]); });
      done += cls.size();
      if (progress)
        progress("optimize: sweep " + std::to_string(sweep + 1), double(done) / order.size());
    }
    stats.visits += visits;
    stats.moves += moves;
    stats.rejected_by_certificate += rejected;
    std::vector<char> next(mesh.num_nodes(), 0);
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if (moved_vertex[v])
        for (const auto& [c, j] : star[v])
          for (int i = 0; i < 4; ++i)
            if (!fixed[corner(c, i)]) next[corner(c, i)] = 1;
    active.clear();
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if (next[v]) active.push_back(v);
  }
  summarize(stats.mean_energy_after, stats.max_energy_after);
  stats.seconds = watch.seconds();
  return stats;
}

}  // namespace curvefem::meshing::curved
