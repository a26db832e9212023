#include "fem/assembly/face_integration.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <array>

#include "fem/assembly/tabulation.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/error.hpp"

namespace curvefem::fem {

void for_each_face_point(const LagrangeMesh& mesh, const FunctionSpace& space,
                         const std::vector<char>& selected, int degree,
                         const std::function<void(int, int, const FacePoint&)>& visit) {
  CF_VERIFY(selected.size() == space.boundary_faces.size(), "face flags do not match the mesh");
  const QuadratureRule& rule = triangle_quadrature(degree);
  const Eigen::Matrix<double, 4, 3> vref =
      (Eigen::Matrix<double, 4, 3>() << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1).finished();
  const Eigen::Matrix<double, 4, 3> nref =  // outward reference normals of the face opposite j
      (Eigen::Matrix<double, 4, 3>() << 1, 1, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1).finished();
  struct FaceTables {
    ReferenceTabulation geometry, basis;
    Eigen::Vector3d ts, tt;
  };
  std::array<FaceTables, 4> tables;
  for (int j = 0; j < 4; ++j) {
    std::array<int, 3> v;
    int n = 0;
    for (int i = 0; i < 4; ++i)
      if (i != j) v[n++] = i;
    Eigen::MatrixXd pts(rule.points.rows(), 3);
    for (int q = 0; q < rule.points.rows(); ++q) {
      const double s = rule.points(q, 0), t = rule.points(q, 1);
      pts.row(q) = (1 - s - t) * vref.row(v[0]) + s * vref.row(v[1]) + t * vref.row(v[2]);
    }
    tables[j].geometry = tabulate(CellKind::tetrahedron, mesh.order, pts);
    tables[j].basis = tabulate(CellKind::tetrahedron, space.degree, pts);
    tables[j].ts = (vref.row(v[1]) - vref.row(v[0])).transpose();
    tables[j].tt = (vref.row(v[2]) - vref.row(v[0])).transpose();
  }
  const int nk = mesh.nodes_per_cell();
  Eigen::Matrix<double, Eigen::Dynamic, 3> X(nk, 3);
  Eigen::VectorXd phi;
  for (std::size_t f = 0; f < space.boundary_faces.size(); ++f) {
    if (!selected[f]) continue;
    const auto [cell, j] = space.boundary_faces[f];
    const FaceTables& tab = tables[j];
    for (int i = 0; i < nk; ++i) X.row(i) = mesh.nodes.row(mesh.cells(cell, i));
    for (int q = 0; q < rule.points.rows(); ++q) {
      const Eigen::Matrix3d J = X.transpose() * tab.geometry.gradients[q];
      Eigen::Vector3d N = (J * tab.ts).cross(J * tab.tt);
      const Eigen::Vector3d outward = J.inverse().transpose() * nref.row(j).transpose();
      if (N.dot(outward) < 0) N = -N;
      FacePoint p;
      p.x = X.transpose() * tab.geometry.values.row(q).transpose();
      const double area = N.norm();
      // Reference triangle (s, t) has area 1/2 and rule weights sum to 1/2: ds = |N| ds_ref.
      p.ds_w = area * rule.weights[q];
      p.normal = area > 0 ? Eigen::Vector3d(N / area) : Eigen::Vector3d::Zero();
      phi = tab.basis.values.row(q).transpose();
      p.phi = phi.data();
      visit(static_cast<int>(f), cell, p);
    }
  }
}

}  // namespace curvefem::fem
