// Harmonic triangulations [Alexa 2019]: flip while it lowers Σ h(t) over the flipped tets.
// One scheduler pass with three operations — 2-3 on interior faces, 3-2 and 4-4 on interior
// edges — each accepted by one invariant: all new tets positive and Σ h(new) < Σ h(old).
// Successful flips renew the faces and edges of their new tets; since every flip strictly lowers
// the total harmonic index, the pass terminates.

#include "meshing/editing/algorithms/harmonic_triangulation.hpp"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <numbers>

#include "meshing/core/error.hpp"
#include "meshing/editing/algorithms/tet_flip_pass.hpp"

namespace curvefem::meshing::editing {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<int, Kernel>;
using Tds = CGAL::Triangulation_data_structure_3<Vb>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;

double harmonic_index(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                      const Eigen::Vector3d& d) {
  const double volume = (b - a).cross(c - a).dot(d - a) / 6.0;
  auto area2 = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
    return 0.25 * (q - p).cross(r - p).squaredNorm();
  };
  return (area2(a, b, c) + area2(a, b, d) + area2(a, c, d) + area2(b, c, d)) / (9.0 * volume);
}

class HarmonicMesh : public TetMesh {
 public:
  Attribute<Eigen::Vector3d> position{*this, 0, Eigen::Vector3d::Zero()};

  bool positive(Id t) const {
    const Cell& c = cell(t);
    return positively_oriented(position[c[0]], position[c[1]], position[c[2]], position[c[3]]);
  }
  double h(Id t) const {
    const Cell& c = cell(t);
    return harmonic_index(position[c[0]], position[c[1]], position[c[2]], position[c[3]]);
  }

 protected:
  bool invariants(const OperationRecord& r) override {
    double before = 0, after = 0;
    for (Id t : r.new_cells) {
      if (!positive(t)) return false;
      after += h(t);
    }
    for (Id t : r.old_cells) before += h(t);
    return after < before * (1.0 - 1e-12);
  }
};

}  // namespace

TetQuality measure_tets(const Eigen::MatrixXd& V, const Eigen::MatrixXi& T) {
  TetQuality q;
  q.tets = std::size_t(T.rows());
  if (T.rows() == 0) return q;
  double edge_sum = 0, h_sum = 0, h_max = 0;
  q.min_dihedral_deg = 180;
  for (int t = 0; t < T.rows(); ++t) {
    Eigen::Vector3d p[4];
    for (int i = 0; i < 4; ++i) p[i] = V.row(T(t, i));
    const double h = harmonic_index(p[0], p[1], p[2], p[3]);
    h_sum += h;
    h_max = std::max(h_max, h);
    q.volume += (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]) / 6.0;
    double tet_min = 180;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        edge_sum += (p[i] - p[j]).norm();
        // Dihedral angle at edge (i, j): between the faces (i, j, k) and (i, j, l).
        int k = 0;
        while (k == i || k == j) ++k;
        int l = 6 - i - j - k;
        const Eigen::Vector3d e = (p[j] - p[i]).normalized();
        Eigen::Vector3d u = p[k] - p[i], w = p[l] - p[i];
        u -= e * e.dot(u);
        w -= e * e.dot(w);
        const double angle = std::atan2(u.cross(w).norm(), u.dot(w)) * 180.0 / std::numbers::pi;
        tet_min = std::min(tet_min, angle);
      }
    q.min_dihedral_deg = std::min(q.min_dihedral_deg, tet_min);
    if (tet_min < 10.0) ++q.slivers;
  }
  const double mean_edge = edge_sum / (6.0 * double(T.rows()));
  q.mean_harmonic_index = h_sum / double(T.rows()) / mean_edge;
  q.max_harmonic_index = h_max / mean_edge;
  return q;
}

HarmonicResult harmonic_triangulation(const Eigen::MatrixXd& points,
                                      const HarmonicOptions& options) {
  if (points.rows() < 4) throw InputError("harmonic triangulation needs at least 4 points");
  HarmonicResult result;
  auto t0 = std::chrono::steady_clock::now();
  std::vector<std::pair<Kernel::Point_3, int>> pts;
  pts.reserve(std::size_t(points.rows()));
  for (int i = 0; i < points.rows(); ++i)
    pts.emplace_back(Kernel::Point_3(points(i, 0), points(i, 1), points(i, 2)), i);
  Delaunay dt(pts.begin(), pts.end());
  if (dt.dimension() != 3) throw InputError("the points are coplanar: no tetrahedralization");
  std::vector<TetMesh::Cell> cells;
  cells.reserve(dt.number_of_finite_cells());
  for (auto c = dt.finite_cells_begin(); c != dt.finite_cells_end(); ++c) {
    // CGAL cells are positively oriented; our convention matches (checked below exactly).
    cells.push_back({Id(c->vertex(0)->info()), Id(c->vertex(1)->info()), Id(c->vertex(2)->info()),
                     Id(c->vertex(3)->info())});
  }
  result.delaunay_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  HarmonicMesh mesh;
  mesh.initialize(std::size_t(points.rows()), cells);
  for (int i = 0; i < points.rows(); ++i) mesh.position.set(Id(i), points.row(i).transpose());
  for (Id t : mesh.live_cells())
    if (!mesh.positive(t))
      throw MeshingError("Delaunay tet " + std::to_string(t) + " is not positively oriented");
  auto export_mesh = [&](Eigen::MatrixXd& V, Eigen::MatrixXi& T) {
    const auto live = mesh.cells_array();
    T.resize(Eigen::Index(live.size()), 4);
    for (std::size_t t = 0; t < live.size(); ++t)
      for (int k = 0; k < 4; ++k) T(Eigen::Index(t), k) = int(live[t][k]);
    V.resize(Eigen::Index(mesh.vertex_capacity()), 3);
    for (std::size_t v = 0; v < mesh.vertex_capacity(); ++v)
      V.row(Eigen::Index(v)) = mesh.position[v].transpose();
  };
  {
    Eigen::MatrixXd V;
    Eigen::MatrixXi T;
    export_mesh(V, T);
    result.before = measure_tets(V, T);
  }

  t0 = std::chrono::steady_clock::now();
  result.passes.emplace_back(
      "flips", run_flip_pass(
                   mesh, [&mesh](Id v) { return mesh.position[v]; }, options.threads));
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  mesh.consolidate();
  export_mesh(result.V, result.T);
  result.after = measure_tets(result.V, result.T);
  return result;
}

}  // namespace curvefem::meshing::editing
