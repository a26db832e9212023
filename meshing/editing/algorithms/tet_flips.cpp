#include "meshing/editing/algorithms/tet_flips.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "meshing/core/error.hpp"
#include "meshing/editing/algorithms/tet_flip_pass.hpp"

namespace curvefem::meshing::editing {

namespace {

const Eigen::Matrix3d& regular_inverse() {
  static const Eigen::Matrix3d inv = [] {
    Eigen::Matrix3d W;
    W.col(0) = Eigen::Vector3d(1, 0, 0);
    W.col(1) = Eigen::Vector3d(0.5, std::sqrt(3.0) / 2, 0);
    W.col(2) = Eigen::Vector3d(0.5, std::sqrt(3.0) / 6, std::sqrt(2.0 / 3.0));
    return Eigen::Matrix3d(W.inverse());
  }();
  return inv;
}

class FlipMesh : public TetMesh {
 public:
  Attribute<Eigen::Vector3d> position{*this, 0, Eigen::Vector3d::Zero()};

  bool positive(Id t) const {
    const Cell& c = cell(t);
    return positively_oriented(position[c[0]], position[c[1]], position[c[2]], position[c[3]]);
  }
  double energy(Id t) const {
    const Cell& c = cell(t);
    return tet_amips(position[c[0]], position[c[1]], position[c[2]], position[c[3]]);
  }

 protected:
  bool invariants(const OperationRecord& r) override {
    double before = 0, after = 0;
    for (Id t : r.old_cells) before = std::max(before, energy(t));
    for (Id t : r.new_cells) {
      if (!positive(t)) return false;
      after = std::max(after, energy(t));
    }
    return after < before * (1.0 - 1e-9);
  }
};

void summarize(const FlipMesh& m, double& mean, double& max) {
  mean = max = 0;
  const auto live = m.live_cells();
  for (Id t : live) {
    const double e = m.energy(t);
    mean += e / double(std::max<std::size_t>(live.size(), 1));
    max = std::max(max, e);
  }
}

}  // namespace

double tet_amips(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 const Eigen::Vector3d& d) {
  Eigen::Matrix3d J;
  J.col(0) = b - a;
  J.col(1) = c - a;
  J.col(2) = d - a;
  J = J * regular_inverse();
  const double det = J.determinant();
  if (!(det > 0)) return std::numeric_limits<double>::infinity();
  return J.squaredNorm() / (3 * std::cbrt(det * det));
}

FlipResult flip_tets(const Eigen::MatrixXd& V, const Eigen::MatrixXi& T,
                     const FlipOptions& options) {
  FlipResult result;
  std::vector<TetMesh::Cell> cells(std::size_t(T.rows()));
  for (int t = 0; t < T.rows(); ++t)
    for (int k = 0; k < 4; ++k) cells[std::size_t(t)][k] = Id(T(t, k));
  FlipMesh mesh;
  mesh.initialize(std::size_t(V.rows()), cells);
  for (int i = 0; i < V.rows(); ++i) mesh.position.set(Id(i), V.row(i).transpose());
  for (Id t : mesh.live_cells())
    if (!mesh.positive(t))
      throw MeshingError("flip_tets: tet " + std::to_string(t) + " is not positively oriented");
  summarize(mesh, result.mean_energy_before, result.max_energy_before);

  // Worst tets first: the priority of a face or edge is the energy of the tet holding it.
  result.pass = run_flip_pass(
      mesh, [&mesh](Id v) { return mesh.position[v]; }, options.threads,
      [&mesh](const TetMesh::Tuple& t) { return mesh.energy(t.tid); });
  summarize(mesh, result.mean_energy_after, result.max_energy_after);
  const auto live = mesh.cells_array();
  result.T.resize(Eigen::Index(live.size()), 4);
  for (std::size_t t = 0; t < live.size(); ++t)
    for (int k = 0; k < 4; ++k) result.T(Eigen::Index(t), k) = int(live[t][k]);
  return result;
}

}  // namespace curvefem::meshing::editing
