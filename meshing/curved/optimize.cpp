#include "meshing/curved/optimize.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <string>

#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/curved/element_distortion.hpp"
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

// One star cell during a visit: the Jacobians at the samples with the moved item at its current
// position, and per sample the row g with dJ = Δ g (a corner moves its star's nodes by their
// barycentric weight, g = ∇λ_jᵀ W⁻¹ at every sample; a single node moves alone, g = ∇N_n(ξ)ᵀ W⁻¹).
struct StarCell {
  int cell;
  std::vector<Eigen::Matrix3d> J0;  // against the regular tet
  std::vector<Eigen::RowVector3d> g;
};

struct StarEnergy {
  double sum = 0, max = 0;  // over the cells' mean energies
  double point_max = 0;     // over the samples
  double variation = 0;     // Σ over the cells of mean |J − J̄|² / |J̄|² (0 for affine maps)
};

// `variation`: also the Jacobian variation (only node moves are judged by it).
StarEnergy star_energy(const std::vector<StarCell>& star, const Eigen::Vector3d& delta,
                       Eigen::Vector3d* gradient, bool variation = false) {
  StarEnergy out;
  if (gradient) gradient->setZero();
  for (const StarCell& s : star) {
    double e = 0;
    Eigen::Vector3d grad_cell = Eigen::Vector3d::Zero();
    if (variation) {
      Eigen::Matrix3d mean = Eigen::Matrix3d::Zero();
      for (std::size_t i = 0; i < s.J0.size(); ++i) mean += s.J0[i] + delta * s.g[i];
      mean /= double(s.J0.size());
      double var = 0;
      for (std::size_t i = 0; i < s.J0.size(); ++i)
        var += (s.J0[i] + delta * s.g[i] - mean).squaredNorm();
      out.variation += var / (double(s.J0.size()) * mean.squaredNorm());
    }
    for (std::size_t i = 0; i < s.J0.size(); ++i) {
      Eigen::Matrix3d dE;
      const double v = amips(s.J0[i] + delta * s.g[i], gradient ? &dE : nullptr);
      if (v == k_inf) return {k_inf, k_inf, k_inf, k_inf};
      e += v;
      out.point_max = std::max(out.point_max, v);
      if (gradient) grad_cell += dE * s.g[i].transpose();
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

// Energy over the order-k lattice (the mean; optionally the worst sample).
double energy_of(const Reference& ref, const Eigen::Ref<const Eigen::MatrixXd>& X,
                 double* point_max = nullptr) {
  double e = 0;
  if (point_max) *point_max = 0;
  for (const Eigen::MatrixXd& G : ref.grads) {
    const Eigen::Matrix3d J = jacobian_at(X, G);
    const double v = amips(J * ref.Winv, nullptr);
    if (point_max) *point_max = std::max(*point_max, v);
    if (v == k_inf) return k_inf;
    e += v;
  }
  return e / double(ref.grads.size());
}

}  // namespace

double cell_energy(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes) {
  CF_VERIFY(order >= 1 && order <= k_max_order, "cell_energy: order outside 1..4");
  static const std::array<Reference, 4> refs = {Reference(1), Reference(2), Reference(3),
                                                Reference(4)};
  const Reference& ref = refs[std::size_t(order - 1)];
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
  const auto& lattice = *ref.lattice;

  // Boundary faces: faces used by one cell only; every node on them is fixed.
  std::map<std::array<int, 3>, std::pair<int, int>> face_count;  // corners → (count, cell·4+skip)
  auto corner = [&](int c, int j) { return mesh.cells(c, ref.corner_row[j]); };
  for (int c = 0; c < nc; ++c)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> f;
      int m = 0;
      for (int j = 0; j < 4; ++j)
        if (j != skip) f[m++] = corner(c, j);
      std::sort(f.begin(), f.end());
      auto& entry = face_count[f];
      ++entry.first;
      entry.second = 4 * c + skip;
    }
  std::vector<char> fixed(mesh.num_nodes(), 0), is_corner(mesh.num_nodes(), 0);
  for (const auto& [f, entry] : face_count)
    if (entry.first == 1) {
      const int c = entry.second / 4, skip = entry.second % 4;
      for (int n = 0; n < ref.nn; ++n)
        if (lattice[n][skip] == 0) fixed[mesh.cells(c, n)] = 1;
    }
  if (frozen) {
    CF_VERIFY(int(frozen->size()) == mesh.num_nodes(), "optimize_vertices: frozen has wrong size");
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if ((*frozen)[std::size_t(v)]) fixed[v] = 1;
  }
  // Stars: a corner's cells with its vertex index, a high-order node's cells with its row.
  std::vector<std::vector<std::pair<int, int>>> star(mesh.num_nodes());
  for (int c = 0; c < nc; ++c)
    for (int j = 0; j < 4; ++j) {
      is_corner[corner(c, j)] = 1;
      star[corner(c, j)].emplace_back(c, j);
    }
  for (int c = 0; c < nc; ++c)
    for (int n = 0; n < ref.nn; ++n)
      if (!is_corner[mesh.cells(c, n)]) star[mesh.cells(c, n)].emplace_back(c, n);

  std::vector<double> energy(nc), point_energy(nc);
  for (int c = 0; c < nc; ++c) energy[c] = energy_of(ref, cell_nodes(mesh, c), &point_energy[c]);
  // Sampled min scaled Jacobian per cell, computed when a move first needs it (NaN: not yet).
  // Only the cells of the visited star are touched, so parallel visits stay disjoint.
  std::vector<double> cell_sj(std::size_t(nc), std::numeric_limits<double>::quiet_NaN());
  auto sj_of = [&](int c) {
    if (std::isnan(cell_sj[std::size_t(c)]))
      cell_sj[std::size_t(c)] = min_scaled_jacobian(k, cell_nodes(mesh, c));
    return cell_sj[std::size_t(c)];
  };
  // The same for the curved MIPS (the quality goal's measure), when options.mips_ceiling > 0.
  std::vector<double> cell_mips(std::size_t(nc), std::numeric_limits<double>::quiet_NaN());
  auto mips_of = [&](int c) {
    if (std::isnan(cell_mips[std::size_t(c)]))
      cell_mips[std::size_t(c)] = curved_mips(k, cell_nodes(mesh, c));
    return cell_mips[std::size_t(c)];
  };
  auto summarize = [&](double& mean, double& max) {
    mean = max = 0;
    for (double e : energy) {
      mean += e / std::max(nc, 1);
      max = std::max(max, e);
    }
  };
  summarize(stats.mean_energy_before, stats.max_energy_before);

  // Curved cells: a node off the linear interpolant of the corners. Single-node moves are made
  // only where a star holds one, so straight parts of the mesh stay straight.
  std::vector<char> curved_cell(nc, 0);
  if (k > 1)
    for (int c = 0; c < nc; ++c) {
      const Eigen::MatrixXd X = cell_nodes(mesh, c);
      const double size = (X.row(ref.corner_row[1]) - X.row(ref.corner_row[0])).norm();
      for (int n = 0; n < ref.nn && !curved_cell[c]; ++n) {
        Eigen::RowVector3d x = Eigen::RowVector3d::Zero();
        for (int j = 0; j < 4; ++j) x += double(lattice[n][j]) / k * X.row(ref.corner_row[j]);
        if ((x - X.row(n)).norm() > 1e-9 * size) curved_cell[c] = 1;
      }
    }

  // One visit of a corner (moving its star's nodes by their barycentric weight) or of a single
  // high-order node; returns whether it moved.
  auto visit = [&](int v, bool corner_move, std::atomic<long long>& rejected) {
    std::vector<StarCell> cells;
    double length = 0;
    int edges = 0;
    for (const auto& [c, local] : star[v]) {
      StarCell s{c, {}, {}};
      const Eigen::MatrixXd X = cell_nodes(mesh, c);
      for (const Eigen::MatrixXd& G : ref.grads) {
        s.J0.push_back((X.transpose() * G) * ref.Winv);
        s.g.push_back(corner_move
                          ? Eigen::RowVector3d(ref.grad_lambda[local].transpose() * ref.Winv)
                          : Eigen::RowVector3d(G.row(local) * ref.Winv));
      }
      cells.push_back(std::move(s));
      // The step scale: a corner's edges, or a node's lattice spacing.
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b)
          if (!corner_move || a == local || b == local) {
            length += (X.row(ref.corner_row[a]) - X.row(ref.corner_row[b])).norm();
            ++edges;
          }
    }
    length /= std::max(edges, 1);
    if (!corner_move) length /= k;
    const StarEnergy start = star_energy(cells, Eigen::Vector3d::Zero(), nullptr, !corner_move);
    if (start.sum == k_inf) return false;  // an uncertifiable star: leave it alone
    Eigen::Vector3d delta = Eigen::Vector3d::Zero();
    StarEnergy current = start;
    for (int it = 0; it < options.iterations; ++it) {
      Eigen::Vector3d g;
      star_energy(cells, delta, &g);
      if (!(g.norm() > 0)) break;
      // Newton direction from a finite-difference Hessian of the analytic gradient, else
      // steepest descent.
      const double h = 1e-6 * length;
      Eigen::Matrix3d H;
      for (int i = 0; i < 3; ++i) {
        Eigen::Vector3d gi;
        star_energy(cells, delta + h * Eigen::Vector3d::Unit(i), &gi);
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
        const StarEnergy trial = star_energy(cells, delta + t * dir, nullptr, !corner_move);
        if (trial.sum < current.sum && trial.max <= start.max &&
            (corner_move || (trial.point_max <= start.point_max &&
                             (trial.variation <= start.variation ||
                              start.point_max > options.node_free_energy)))) {
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
    if (!(start.sum - current.sum > options.tolerance * start.sum) || delta.isZero(0)) return false;

    std::vector<std::pair<int, double>> moved;  // node, weight (of k) of the move
    if (corner_move) {
      for (const auto& [c, j] : star[v])
        for (int n = 0; n < ref.nn; ++n)
          if (lattice[n][j] > 0) moved.emplace_back(mesh.cells(c, n), lattice[n][j]);
      std::sort(moved.begin(), moved.end());
      moved.erase(std::unique(moved.begin(), moved.end(),
                              [](const auto& a, const auto& b) { return a.first == b.first; }),
                  moved.end());
    } else {
      moved.emplace_back(v, k);
    }
    // Apply, certify every star cell, restore the saved rows exactly on failure (halving the
    // move a few times while it still improves the search energy).
    std::vector<Eigen::RowVector3d> saved;
    for (const auto& [node, a] : moved) saved.push_back(mesh.nodes.row(node));
    auto restore = [&] {
      for (std::size_t i = 0; i < moved.size(); ++i) mesh.nodes.row(moved[i].first) = saved[i];
    };
    double sj_before = k_inf, mips_before = 0;
    for (const auto& [c, local] : star[v]) {
      sj_before = std::min(sj_before, sj_of(c));
      if (options.mips_ceiling > 0) mips_before = std::max(mips_before, mips_of(c));
    }
    const double sj_floor = std::min(sj_before, options.scaled_jacobian_floor);
    const double mips_cap = std::max(mips_before, options.mips_ceiling);
    std::vector<double> sj_after(star[v].size()), mips_after(star[v].size(), 0.0);
    bool accepted = false;
    for (int attempt = 0; attempt < 4; ++attempt) {
      for (std::size_t i = 0; i < moved.size(); ++i)
        mesh.nodes.row(moved[i].first) = saved[i] + (moved[i].second / k) * delta.transpose();
      accepted = true;
      for (std::size_t i = 0; i < star[v].size() && accepted; ++i) {
        const Eigen::MatrixXd X = cell_nodes(mesh, star[v][i].first);
        sj_after[i] = min_scaled_jacobian(k, X);
        if (options.mips_ceiling > 0) mips_after[i] = curved_mips(k, X);
        accepted = sj_after[i] >= sj_floor &&
                   certify_tet_jacobian(k, X).verdict == JacobianVerdict::positive;
      }
      // The MIPS cap binds only moves that do not raise the star's worst scaled Jacobian (those
      // are what the goal needs most; capped, abc_00000008's worst cell fell 3.3e-4 -> 5.8e-5).
      if (accepted && options.mips_ceiling > 0 &&
          *std::max_element(mips_after.begin(), mips_after.end()) > mips_cap &&
          !(*std::min_element(sj_after.begin(), sj_after.end()) > sj_before))
        accepted = false;
      if (accepted) break;
      ++rejected;
      restore();
      delta *= 0.5;
      const StarEnergy half = star_energy(cells, delta, nullptr, !corner_move);
      if (!(start.sum - half.sum > options.tolerance * start.sum && half.max <= start.max &&
            (corner_move ||
             (half.point_max <= start.point_max &&
              (half.variation <= start.variation || start.point_max > options.node_free_energy)))))
        break;
    }
    if (!accepted) return false;
    for (std::size_t i = 0; i < star[v].size(); ++i) {
      const int c = star[v][i].first;
      energy[c] = energy_of(ref, cell_nodes(mesh, c), &point_energy[c]);
      cell_sj[std::size_t(c)] = sj_after[i];
      cell_mips[std::size_t(c)] =
          options.mips_ceiling > 0 ? mips_after[i] : std::numeric_limits<double>::quiet_NaN();
    }
    return true;
  };

  // The search for the worst cells (OptimizeOptions::worst_sweeps): one corner moves its star's
  // nodes by their barycentric weight, as in visit(), to raise the star's minimum sampled scaled
  // Jacobian. A straight cell stays straight under such a move, so its corners alone give it.
  // Per curved cell, the lattice points of its last four distinct minima (worst_visit's quick
  // rejection; stars of one colour class share no cell, so parallel visits write disjoint
  // entries).
  std::vector<std::array<int, 4>> cell_hint(std::size_t(nc), std::array<int, 4>{-1, -1, -1, -1});
  auto cell_sj_now = [&](int c) {
    if (curved_cell[c] || k == 1) return min_scaled_jacobian(k, cell_nodes(mesh, c));
    Eigen::Matrix<double, 4, 3> X;
    for (int j = 0; j < 4; ++j) X.row(j) = mesh.nodes.row(corner(c, j));
    return min_scaled_jacobian(1, X);
  };
  // A high-order node off the boundary moves alone (its cells become curved): that reaches a
  // cell whose corners cannot move without inverting it, such as a slab tet under a curved
  // boundary face.
  // by_mips: the same search lowers the star's worst curved MIPS instead (OptimizeOptions::
  // worst_mips), keeping every cell's scaled Jacobian above min(the star's before, the worst
  // search's threshold): a near-flat cell's MIPS can be far above the goal while its sampled
  // scaled Jacobian is above that threshold (thin_plate_05, K = 3: MIPS 1.03e4 at 0.027).
  // mean (OptimizeOptions::mean_sweeps): the star's summed curved MIPS instead, its worst cell's
  // scaled Jacobian and curved MIPS no worse than before.
  auto worst_visit = [&](int v, std::atomic<long long>& rejected, bool by_mips, bool mean) {
    by_mips = by_mips || mean;
    const bool corner_move = is_corner[v];
    std::vector<std::pair<int, double>> moved;  // node, weight (of k)
    std::vector<std::pair<double, int>> cells;  // scaled Jacobian before, cell; worst first
    double length = 0;
    for (const auto& [c, j] : star[v]) {
      cells.emplace_back(sj_of(c), c);
      if (corner_move) {
        for (int n = 0; n < ref.nn; ++n)
          if (lattice[n][j] > 0) moved.emplace_back(mesh.cells(c, n), lattice[n][j]);
        for (int a = 0; a < 4; ++a)
          if (a != j) length += (mesh.nodes.row(corner(c, a)) - mesh.nodes.row(v)).norm();
      } else {
        for (int a = 0; a < 4; ++a)
          for (int b = a + 1; b < 4; ++b)
            length += (mesh.nodes.row(corner(c, a)) - mesh.nodes.row(corner(c, b))).norm() / 2;
      }
    }
    if (corner_move) {
      length /= 3.0 * double(star[v].size());
    } else {
      moved.emplace_back(v, k);
      length /= 3.0 * double(k) * double(star[v].size());
      // Its cells are curved from the first trial on (corner visits then evaluate them whole).
      for (const auto& [c, j] : star[v]) curved_cell[c] = 1;
    }
    std::sort(cells.begin(), cells.end());
    std::sort(moved.begin(), moved.end());
    moved.erase(std::unique(moved.begin(), moved.end(),
                            [](const auto& a, const auto& b) { return a.first == b.first; }),
                moved.end());
    std::vector<Eigen::RowVector3d> saved;
    for (const auto& [node, a] : moved) saved.push_back(mesh.nodes.row(node));
    auto place = [&](const Eigen::Vector3d& d) {
      for (std::size_t i = 0; i < moved.size(); ++i)
        mesh.nodes.row(moved[i].first) = saved[i] + (moved[i].second / k) * d.transpose();
    };
    // The star's minimum at d, or -inf as soon as a cell is at or below `bar`: worst cells are
    // evaluated first, so most failing trials stop after one or two. Before that, every curved
    // cell is tried at the lattice points where its last full evaluations found their minima
    // (cell_hint): a value there below the bar (by more than rounding; scaled_jacobian_at sums
    // the same terms in the same order) means the cell's minimum is below too, and the trial
    // fails as the full evaluations would have made it fail, at a few 220ths of a cell's cost
    // at K = 4. tr12j_occt K = 4 (1 thread): the worst-cell search 48.5 -> 15 s, 1.3 of its
    // 1.8 million trials rejected that way, the same mesh.
    std::vector<double> trial_sj(cells.size()), trial_mips(cells.size());
    std::vector<Eigen::MatrixXd> nodes_of(cells.size(), Eigen::MatrixXd(mesh.cells.cols(), 3));
    // (At the start position: the search below moves the nodes.)
    double mips_sum_before = 0, mips_max_before = 0;
    for (const auto& [q, c] : cells) {
      mips_sum_before += mips_of(c);
      mips_max_before = std::max(mips_max_before, mips_of(c));
    }
    // mean: a guard per cell, so that no cell pays for the sum: none may fall below min(its
    // scaled Jacobian before, mean_sj_floor) nor rise above max(its curved MIPS before,
    // mean_mips_above). (The star's minimum and maximum alone let a cell other than the worst
    // fall to the worst's value: octocat K = 4, the slab's min scaled Jacobian 1.8e-3 ->
    // 2.2e-4.)
    std::vector<double> mips_bar(cells.size(), mips_max_before);
    std::vector<double> sj_bar_of(cells.size());
    if (mean)
      for (std::size_t i = 0; i < cells.size(); ++i)
        mips_bar[i] = std::max(mips_of(cells[i].second), options.mean_mips_above);
    // by_mips: no cell's scaled Jacobian at or below sj_floor (with the slack where the star's
    // worst cell is above worst_mips_slack_above); the value is minus the worst MIPS (from the
    // nodes value() gathered).
    const double sj_keep = std::min(cells.front().first, options.worst_scaled_jacobian);
    const double sj_floor = mean ? cells.front().first
                            : by_mips && mips_max_before > options.worst_mips_slack_above
                                ? std::max((1 - options.worst_mips_sj_slack) * sj_keep,
                                           std::min(cells.front().first, 2e-3))
                                : sj_keep;
    for (std::size_t i = 0; i < cells.size(); ++i)
      sj_bar_of[i] = mean ? std::min(cells[i].first, options.mean_sj_floor) : sj_floor;
    // by_mips: each cell's Jacobians at curved_mips' samples at the start, and their change per
    // unit move (J(d) = J0 + d gᵀ, g = Σ of the moved nodes' weight times their shape gradient),
    // so that a trial's curved MIPS costs a rank-one update per sample instead of a sum over the
    // cell's nodes (the accepted move's values are computed from the nodes again, below).
    const std::vector<Eigen::MatrixXd>& mips_grads = curved_mips_gradients(k);
    const std::size_t ns = mips_grads.size();
    std::vector<Eigen::Matrix3d> mips_J0;
    std::vector<Eigen::Vector3d> mips_g;
    if (by_mips) {
      mips_J0.resize(cells.size() * ns);
      mips_g.resize(cells.size() * ns);
      Eigen::VectorXd w(mesh.cells.cols());
      for (std::size_t i = 0; i < cells.size(); ++i) {
        const int c = cells[i].second;
        const Eigen::MatrixXd X = cell_nodes(mesh, c);
        for (Eigen::Index n = 0; n < w.size(); ++n) {
          const auto it = std::lower_bound(moved.begin(), moved.end(),
                                           std::make_pair(mesh.cells(c, n), -k_inf));
          w[n] = it != moved.end() && it->first == mesh.cells(c, n) ? it->second / k : 0.0;
        }
        for (std::size_t p = 0; p < ns; ++p) {
          mips_J0[i * ns + p] = jacobian_at(X, mips_grads[p]);
          mips_g[i * ns + p] = mips_grads[p].transpose() * w;
        }
      }
    }
    auto trial_cell_mips = [&](std::size_t i, const Eigen::Vector3d& d) {
      double sum = 0;
      for (std::size_t p = 0; p < ns; ++p) {
        const double term =
            curved_mips_term(mips_J0[i * ns + p] + d * mips_g[i * ns + p].transpose());
        if (term == k_inf) return k_inf;
        sum += term;
      }
      return sum / double(ns);
    };
    // mean, a single node moved (OptimizeOptions::mean_variation_guard): no star cell's Jacobian
    // variation Σ|J − J̄|²/|J̄|² over the same samples may grow (as in the node phase): the MIPS
    // alone bought its fall with the maps' higher derivatives, and the FEM error on those maps
    // rose (the geometry matrix's cylinder, k = 4, p = 3 elasticity L2 7.4e-3 -> 1.5e-1).
    const bool guard_variation = mean && !corner_move && options.mean_variation_guard;
    auto cell_variation = [&](std::size_t i, const Eigen::Vector3d& d) {
      Eigen::Matrix3d mean_J = Eigen::Matrix3d::Zero();
      for (std::size_t p = 0; p < ns; ++p)
        mean_J += mips_J0[i * ns + p] + d * mips_g[i * ns + p].transpose();
      mean_J /= double(ns);
      double var = 0;
      for (std::size_t p = 0; p < ns; ++p)
        var += (mips_J0[i * ns + p] + d * mips_g[i * ns + p].transpose() - mean_J).squaredNorm();
      return var / (double(ns) * mean_J.squaredNorm());
    };
    std::vector<double> variation_before(guard_variation ? cells.size() : 0);
    for (std::size_t i = 0; i < variation_before.size(); ++i)
      variation_before[i] = cell_variation(i, Eigen::Vector3d::Zero());
    // And no cell's distortion d2, d3 (element_distortion.hpp: ‖D²F‖‖DF⁻¹‖, ‖D³F‖‖DF⁻¹‖, what
    // the FEM error constants carry) may grow.
    std::vector<ElementDistortion> distortion_before(guard_variation ? cells.size() : 0);
    for (std::size_t i = 0; i < distortion_before.size(); ++i)
      distortion_before[i] = element_distortion(k, cell_nodes(mesh, cells[i].second));
    auto variation_kept = [&](const Eigen::Vector3d& d) {
      for (std::size_t i = 0; i < variation_before.size(); ++i)
        if (!(cell_variation(i, d) <= variation_before[i])) return false;
      return true;
    };
    auto mips_value = [&](const Eigen::Vector3d& d, double bar) {
      double worst = 0, sum = 0;
      for (std::size_t i = 0; i < cells.size(); ++i) {
        trial_mips[i] = trial_cell_mips(i, d);
        if (mean ? !(trial_mips[i] <= mips_bar[i]) : !(-trial_mips[i] > bar)) return -k_inf;
        worst = std::max(worst, trial_mips[i]);
        sum += trial_mips[i];
        if (mean && !(-sum > bar)) return -k_inf;  // already no better than the best so far
      }
      if (guard_variation && !variation_kept(d)) return -k_inf;
      return mean ? -sum : -worst;
    };
    auto value = [&](const Eigen::Vector3d& d, double bar) {
      // mean: the summed MIPS first (most trials fail it, and it stops at the first cell that
      // takes the sum past the best), the scaled Jacobians only for a better sum.
      double mean_value = 0;
      if (mean && (mean_value = mips_value(d, bar)) == -k_inf) return -k_inf;
      place(d);
      // Each curved cell's nodes are gathered once per trial, into buffers kept over the visit.
      for (std::size_t i = 0; i < cells.size(); ++i)
        if (curved_cell[cells[i].second] && k > 1)
          for (Eigen::Index n = 0; n < mesh.cells.cols(); ++n)
            nodes_of[i].row(n) = mesh.nodes.row(mesh.cells(cells[i].second, n));
      // Any cell clearly below the bar at its hint fails the trial, whichever cell the full
      // evaluations below would have stopped at.
      auto sj_bar = [&](std::size_t i) { return by_mips ? sj_bar_of[i] : bar; };
      for (std::size_t i = 0; i < cells.size(); ++i) {
        const int c = cells[i].second;
        if (!curved_cell[c] || k == 1) continue;
        const double clearly_below = sj_bar(i) - 1e-12 * std::abs(sj_bar(i)) - 1e-300;
        for (int j : cell_hint[std::size_t(c)])
          if (j >= 0 && scaled_jacobian_at(k, nodes_of[i], j) < clearly_below) return -k_inf;
      }
      double m = k_inf;
      for (std::size_t i = 0; i < cells.size(); ++i) {
        const int c = cells[i].second;
        if (curved_cell[c] && k > 1) {
          int at = -1;
          trial_sj[i] = min_scaled_jacobian(k, nodes_of[i], &at);
          std::array<int, 4>& h = cell_hint[std::size_t(c)];
          if (std::find(h.begin(), h.end(), at) == h.end()) h = {at, h[0], h[1], h[2]};
        } else {
          trial_sj[i] = cell_sj_now(c);
        }
        if (!(trial_sj[i] > sj_bar(i))) return -k_inf;
        m = std::min(m, trial_sj[i]);
      }
      for (std::size_t i = 0; i < distortion_before.size(); ++i) {
        if (!curved_cell[cells[i].second] || k == 1) continue;  // straight, and stays so
        const ElementDistortion e = element_distortion(k, nodes_of[i]);
        if (!(e.d2 <= distortion_before[i].d2 && e.d3 <= distortion_before[i].d3)) return -k_inf;
      }
      return mean ? mean_value : by_mips ? mips_value(d, bar) : m;
    };
    static const std::array<Eigen::Vector3d, 14> directions = [] {
      std::array<Eigen::Vector3d, 14> d;
      for (int i = 0; i < 3; ++i) {
        d[std::size_t(2 * i)] = Eigen::Vector3d::Unit(i);
        d[std::size_t(2 * i + 1)] = -Eigen::Vector3d::Unit(i);
      }
      for (int i = 0; i < 8; ++i)
        d[std::size_t(6 + i)] =
            Eigen::Vector3d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1) / std::sqrt(3.0);
      return d;
    }();
    const double before = mean      ? -mips_sum_before
                          : by_mips ? -mips_max_before
                                    : cells.front().first;
    double best = before;
    Eigen::Vector3d delta = Eigen::Vector3d::Zero();
    int evaluations = 0;
    const int max_evaluations = mean ? options.mean_evaluations : 200;
    for (double h = 0.25 * length; h > 1e-3 * length && evaluations < max_evaluations;) {
      bool improved = false;
      for (const Eigen::Vector3d& d : directions) {
        ++evaluations;
        const double q = value(delta + h * d, best);
        if (q > best) {
          best = q;
          delta += h * d;
          improved = true;
          break;
        }
      }
      if (!improved) h *= 0.5;
    }
    // A gain of less than 5% is not worth a certificate. The minimum alone would trade the other
    // cells' shape for it (tr12j_occt K = 3: mean curved MIPS 322 -> 358), so the star's summed
    // curved MIPS may not grow, nor its worst above max(its value before, mips_ceiling).
    // (by_mips: the values are negative, so the worst MIPS must fall below before / 1.05.)
    const double gain = mean ? 1.0 / 1.01 : by_mips ? 1.0 / 1.05 : 1.05;
    const double mips_cap =
        mean ? mips_max_before : std::max(mips_max_before, options.mips_ceiling);
    std::vector<double> mips_after(cells.size());
    bool accepted = false;
    for (int attempt = 0; attempt < 4 && !accepted; ++attempt) {
      if (attempt > 0) delta *= 0.5;
      if (!(value(delta, gain * before) > gain * before)) break;
      double sum = 0, max = 0;
      for (std::size_t i = 0; i < cells.size(); ++i) {
        mips_after[i] = curved_mips(k, cell_nodes(mesh, cells[i].second));
        sum += mips_after[i];
        max = std::max(max, mips_after[i]);
      }
      int flat_before = 0, flat_after = 0;
      for (std::size_t i = 0; i < cells.size(); ++i) {
        flat_before += cells[i].first < options.worst_flat;
        flat_after += trial_sj[i] < options.worst_flat;
      }
      accepted = sum <= mips_sum_before && max <= mips_cap && flat_after <= flat_before;
      for (std::size_t i = 0; i < cells.size() && accepted && mean; ++i)
        accepted = mips_after[i] <= mips_bar[i] && trial_sj[i] >= sj_bar_of[i];
      for (std::size_t i = 0; i < cells.size() && accepted; ++i)
        accepted = certify_tet_jacobian(k, cell_nodes(mesh, cells[i].second)).verdict ==
                   JacobianVerdict::positive;
      if (!accepted) ++rejected;
    }
    if (!accepted) {
      place(Eigen::Vector3d::Zero());
      return false;
    }
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const int c = cells[i].second;
      energy[c] = energy_of(ref, cell_nodes(mesh, c), &point_energy[c]);
      cell_sj[std::size_t(c)] = trial_sj[i];
      cell_mips[std::size_t(c)] = mips_after[i];
    }
    return true;
  };

  // Sweeps over the active items, worst stars first; the next sweep's items are those of the
  // cells a move changed. Items whose stars share no cell touch disjoint nodes and energies, so
  // a colour class is visited in parallel with the same result as serially, for any thread count.
  struct Sweeps {
    int movable = 0, sweeps = 0;
    long long visits = 0, moves = 0, rejected = 0;
  };
  using Visit = std::function<bool(int, std::atomic<long long>&)>;
  // max_items > 0: each sweep visits at most that many items, the first in key order.
  auto run = [&](const Visit& visit_item, int max_sweeps, const std::function<bool(int)>& eligible,
                 const std::function<double(int)>& key, const std::string& label,
                 std::size_t max_items = 0) {
    Sweeps out;
    std::vector<int> active;
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if (eligible(v)) active.push_back(v);
    out.movable = int(active.size());
    for (int sweep = 0; sweep < max_sweeps && !active.empty(); ++sweep) {
      ++out.sweeps;
      std::vector<std::pair<double, int>> order;
      for (int v : active) order.emplace_back(key(v), v);
      std::sort(order.begin(), order.end());
      if (max_items > 0 && order.size() > max_items) order.resize(max_items);
      std::vector<std::vector<int>> cell_colours(nc), classes;
      for (const auto& [neg, v] : order) {
        std::vector<char> used(classes.size() + 1, 0);
        for (const auto& [c, local] : star[v])
          for (int col : cell_colours[c]) used[col] = 1;
        int col = 0;
        while (used[col]) ++col;
        for (const auto& [c, local] : star[v]) cell_colours[c].push_back(col);
        if (col == int(classes.size())) classes.emplace_back();
        classes[col].push_back(v);
      }
      std::vector<char> moved_item(mesh.num_nodes(), 0);
      std::atomic<long long> moves{0}, rejected{0};
      std::size_t done = 0;
      for (const auto& cls : classes) {
        tbb::parallel_for(std::size_t(0), cls.size(), [&](std::size_t i) {
          if (visit_item(cls[i], rejected)) {
            moved_item[cls[i]] = 1;
            ++moves;
          }
        });
        done += cls.size();
        if (progress)
          progress("optimize: " + label + " sweep " + std::to_string(sweep + 1),
                   double(done) / order.size());
      }
      out.visits += (long long)order.size();
      out.moves += moves;
      out.rejected += rejected;
      std::vector<char> next(mesh.num_nodes(), 0);
      for (int v = 0; v < mesh.num_nodes(); ++v)
        if (moved_item[v])
          for (const auto& [c, local] : star[v])
            for (int n = 0; n < ref.nn; ++n) next[mesh.cells(c, n)] = 1;
      active.clear();
      for (int v = 0; v < mesh.num_nodes(); ++v)
        if (next[v] && eligible(v)) active.push_back(v);
    }
    return out;
  };

  // Worst star first (the order only decides which of two overlapping stars goes first).
  auto worst_energy_first = [&](int v) {
    double worst = 0;
    for (const auto& [c, local] : star[v]) worst = std::max(worst, energy[c]);
    return -worst;
  };
  const Sweeps a =
      run([&](int v, std::atomic<long long>& r) { return visit(v, true, r); }, options.sweeps,
          [&](int v) { return is_corner[v] && !fixed[v]; }, worst_energy_first, "vertex");
  stats.movable_vertices = a.movable;
  stats.sweeps = a.sweeps;
  stats.visits = a.visits;
  stats.moves = a.moves;
  stats.rejected_by_certificate = a.rejected;

  if (k > 1 && options.node_sweeps > 0) {
    auto node_eligible = [&](int v) {
      if (is_corner[v] || fixed[v]) return false;
      bool curved = false;
      double worst = 0;
      for (const auto& [c, local] : star[v]) {
        curved = curved || curved_cell[c];
        worst = std::max(worst, point_energy[c]);
      }
      return curved && worst > options.node_energy;
    };
    const Sweeps b = run([&](int v, std::atomic<long long>& r) { return visit(v, false, r); },
                         options.node_sweeps, node_eligible, worst_energy_first, "node");
    stats.movable_nodes = b.movable;
    stats.node_sweeps = b.sweeps;
    stats.node_visits = b.visits;
    stats.node_moves = b.moves;
    stats.rejected_by_certificate += b.rejected;
  }
  // (The mean polish runs on the same set-up, also without the worst-cell sweeps.)
  if (options.worst_sweeps > 0 || options.mean_sweeps > 0) {
    Stopwatch worst_watch;
    tbb::parallel_for(0, nc, [&](int c) { sj_of(c); });
    stats.worst_sj_before = std::min(1.0, *std::min_element(cell_sj.begin(), cell_sj.end()));
    auto star_min_sj = [&](int v) {
      double m = k_inf;
      for (const auto& [c, local] : star[v]) m = std::min(m, sj_of(c));
      return m;
    };
    // Corners, and the high-order nodes of stars holding a curved cell (straight parts stay
    // straight, as in the node phase).
    std::vector<char> node_ok(std::size_t(mesh.num_nodes()), 0);
    for (int v = 0; v < mesh.num_nodes(); ++v)
      if (!is_corner[v] && k > 1)
        for (const auto& [c, local] : star[v]) node_ok[std::size_t(v)] |= curved_cell[c];
    auto worst_eligible = [&](int v) {
      return (is_corner[v] || node_ok[std::size_t(v)]) && !fixed[v] &&
             star_min_sj(v) < options.worst_scaled_jacobian;
    };
    const Sweeps w =
        run([&](int v, std::atomic<long long>& r) { return worst_visit(v, r, false, false); },
            options.worst_sweeps, worst_eligible, star_min_sj, "worst");
    stats.worst_movable = w.movable;
    stats.worst_sweeps = w.sweeps;
    stats.worst_visits = w.visits;
    stats.worst_moves = w.moves;
    stats.rejected_by_certificate += w.rejected;
    stats.worst_sj_after = std::min(1.0, *std::min_element(cell_sj.begin(), cell_sj.end()));
    auto star_max_mips = [&](int v) {
      double m = 0;
      for (const auto& [c, local] : star[v]) m = std::max(m, mips_of(c));
      return m;
    };
    if (options.worst_mips > 0) {
      auto mips_eligible = [&](int v) {
        return (is_corner[v] || node_ok[std::size_t(v)]) && !fixed[v] &&
               star_max_mips(v) > options.worst_mips;
      };
      for (int c = 0; c < nc; ++c)
        stats.worst_mips_before = std::max(stats.worst_mips_before, mips_of(c));
      const Sweeps x =
          run([&](int v, std::atomic<long long>& r) { return worst_visit(v, r, true, false); },
              options.worst_sweeps, mips_eligible, [&](int v) { return -star_max_mips(v); },
              "worst MIPS", std::size_t(std::max(0, options.worst_mips_visits)));
      stats.worst_mips_movable = x.movable;
      stats.worst_mips_visits = x.visits;
      stats.worst_mips_moves = x.moves;
      stats.rejected_by_certificate += x.rejected;
      for (int c = 0; c < nc; ++c)
        stats.worst_mips_after = std::max(stats.worst_mips_after, mips_of(c));
      stats.worst_sj_after = std::min(1.0, *std::min_element(cell_sj.begin(), cell_sj.end()));
    }
    if (options.mean_sweeps > 0) {
      // Last, the mean: stars holding a cell above mean_mips_above, their summed curved MIPS
      // lowered without their worst cell getting worse (OptimizeOptions::mean_sweeps).
      auto mean_mips = [&] {
        double sum = 0;
        for (int c = 0; c < nc; ++c) sum += mips_of(c);
        return sum / std::max(nc, 1);
      };
      stats.mean_mips_before = mean_mips();
      const Sweeps y =
          run([&](int v, std::atomic<long long>& r) { return worst_visit(v, r, false, true); },
              options.mean_sweeps,
              [&](int v) {
                return (is_corner[v] || node_ok[std::size_t(v)]) && !fixed[v] &&
                       star_max_mips(v) > options.mean_mips_above;
              },
              [&](int v) { return -star_max_mips(v); }, "mean MIPS");
      stats.mean_mips_movable = y.movable;
      stats.mean_mips_visits = y.visits;
      stats.mean_mips_moves = y.moves;
      stats.mean_variation_guard = options.mean_variation_guard;
      stats.rejected_by_certificate += y.rejected;
      stats.mean_mips_after = mean_mips();
    }
    stats.worst_seconds = worst_watch.seconds();
  }
  summarize(stats.mean_energy_after, stats.max_energy_after);
  stats.seconds = watch.seconds();
  return stats;
}

}  // namespace curvefem::meshing::curved
