// QSlim [Garland & Heckbert 1997]: every vertex carries the quadric of the planes of its faces;
// collapsing edge (a, b) costs min_x [x;1]ᵀ(Q_a + Q_b)[x;1], attained at the optimal placement x
// (the solution of the 3x3 system, or the best of a, b and the midpoint when it is singular).
// Edges are collapsed cheapest first; the kept vertex gets Q_a + Q_b and its edges are re-queued.

#include <Eigen/Dense>
#include <memory>

#include "meshing/editing/algorithms/surface_passes.hpp"

namespace curvefem::meshing::editing {

namespace {

class QSlimMesh : public SurfaceEditMesh {
 public:
  Attribute<Eigen::Matrix4d> quadric{*this, 0, Eigen::Matrix4d::Zero()};

  void init_quadrics() {
    for (std::size_t v = 0; v < vertex_capacity(); ++v) quadric.set(v, Eigen::Matrix4d::Zero());
    for (Id f : live_cells()) {
      const Eigen::Vector3d n = face_normal(f);
      const double len = n.norm();
      if (len == 0) continue;
      Eigen::Vector4d plane;
      plane << n / len, -(n / len).dot(position[cell(f)[0]]);
      const Eigen::Matrix4d K = plane * plane.transpose();
      for (Id v : cell(f)) quadric.set(v, quadric[v] + K);
    }
  }
  // Optimal placement and its cost.
  std::pair<Eigen::Vector3d, double> best(Id a, Id b) const {
    const Eigen::Matrix4d Q = quadric[a] + quadric[b];
    auto cost = [&](const Eigen::Vector3d& x) {
      Eigen::Vector4d h;
      h << x, 1.0;
      return h.dot(Q * h);
    };
    const Eigen::Matrix3d A = Q.topLeftCorner<3, 3>();
    const Eigen::Vector3d rhs = -Q.topRightCorner<3, 1>();
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
    if (lu.rank() == 3 && lu.rcond() > 1e-10) {
      const Eigen::Vector3d x = lu.solve(rhs);
      return {x, cost(x)};
    }
    const Eigen::Vector3d cands[3] = {position[a], position[b], 0.5 * (position[a] + position[b])};
    std::pair<Eigen::Vector3d, double> out{cands[0], cost(cands[0])};
    for (const auto& c : cands)
      if (double k = cost(c); k < out.second) out = {c, k};
    return out;
  }

 protected:
  Eigen::Vector3d collapse_position(Id removed, Id kept) const override {
    return best(removed, kept).first;
  }
  void collapse_update(const OperationRecord& r) override {
    quadric.set(r.v1, quadric[r.v0] + quadric[r.v1]);
  }
};

}  // namespace

std::unique_ptr<SurfaceEditMesh> make_qslim_mesh() { return std::make_unique<QSlimMesh>(); }

void qslim(SurfaceEditMesh& base, std::size_t target_faces, int threads, PassLog& log) {
  auto& m = dynamic_cast<QSlimMesh&>(base);
  m.init_quadrics();
  run_collapse_pass(
      m, [&m](const TriMesh::Tuple& t) { return m.best(t.vid, m.other_vertex(t)).second; },
      target_faces, threads, "qslim", log);
}

}  // namespace curvefem::meshing::editing
