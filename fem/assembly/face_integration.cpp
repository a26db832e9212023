#include "fem/assembly/face_integration.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <array>

#include "fem/assembly/tabulation.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/error.hpp"

namespace curvefem::fem {

FacePoint FacePoints::point(int k) const {
  FacePoint p;
  p.x = x.row(k).transpose();
  p.normal = normal.row(k).transpose();
  p.ds_w = ds_w[k];
  p.phi = basis.row(basis_row[k]).data();
  return p;
}

FacePoints face_points(const LagrangeMesh& mesh, const FunctionSpace& space,
                       const std::vector<char>& selected, int degree, bool with_gradients) {
  CF_VERIFY(selected.size() == space.boundary_faces.size(), "face flags do not match the mesh");
  const QuadratureRule& rule = triangle_quadrature(degree);
  const int nq = rule.size();
  const Eigen::Matrix<double, 4, 3> vref =
      (Eigen::Matrix<double, 4, 3>() << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1).finished();
  const Eigen::Matrix<double, 4, 3> nref =  // outward reference normals of the face opposite j
      (Eigen::Matrix<double, 4, 3>() << 1, 1, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1).finished();
  struct FaceTables {
    ReferenceTabulation geometry, space;  // space: only with gradients
    Eigen::Vector3d ts, tt;
  };
  std::array<FaceTables, 4> tables;
  FacePoints out;
  out.basis.resize(4 * nq, num_lagrange_nodes(CellKind::tetrahedron, space.degree));
  for (int j = 0; j < 4; ++j) {
    std::array<int, 3> v;
    int n = 0;
    for (int i = 0; i < 4; ++i)
      if (i != j) v[n++] = i;
    Eigen::MatrixXd pts(nq, 3);
    for (int q = 0; q < nq; ++q) {
      const double s = rule.points(q, 0), t = rule.points(q, 1);
      pts.row(q) = (1 - s - t) * vref.row(v[0]) + s * vref.row(v[1]) + t * vref.row(v[2]);
    }
    tables[j].geometry = tabulate(CellKind::tetrahedron, mesh.order, pts);
    ReferenceTabulation basis = tabulate(CellKind::tetrahedron, space.degree, pts);
    out.basis.middleRows(j * nq, nq) = basis.values;
    if (with_gradients) tables[j].space = std::move(basis);
    tables[j].ts = (vref.row(v[1]) - vref.row(v[0])).transpose();
    tables[j].tt = (vref.row(v[2]) - vref.row(v[0])).transpose();
  }
  std::vector<int> faces;
  for (std::size_t f = 0; f < space.boundary_faces.size(); ++f)
    if (selected[f]) faces.push_back(static_cast<int>(f));
  const int total = static_cast<int>(faces.size()) * nq;
  out.x.resize(total, 3);
  out.normal.resize(total, 3);
  out.ds_w.resize(total);
  out.face.resize(total);
  out.cell.resize(total);
  out.basis_row.resize(total);
  if (with_gradients) out.gradients.resize(std::size_t(total));
  const int nk = mesh.nodes_per_cell();
  tbb::parallel_for(
      tbb::blocked_range<int>(0, static_cast<int>(faces.size()), 64),
      [&](const tbb::blocked_range<int>& range) {
        Eigen::Matrix<double, Eigen::Dynamic, 3> X(nk, 3);
        for (int i = range.begin(); i < range.end(); ++i) {
          const int f = faces[i];
          const auto [cell, j] = space.boundary_faces[f];
          const FaceTables& tab = tables[j];
          for (int a = 0; a < nk; ++a) X.row(a) = mesh.nodes.row(mesh.cells(cell, a));
          for (int q = 0; q < nq; ++q) {
            const int k = i * nq + q;
            const Eigen::Matrix3d J = X.transpose() * tab.geometry.gradients[q];
            Eigen::Vector3d N = (J * tab.ts).cross(J * tab.tt);
            const Eigen::Matrix3d Jinv = J.inverse();
            const Eigen::Vector3d outward = Jinv.transpose() * nref.row(j).transpose();
            if (N.dot(outward) < 0) N = -N;
            out.x.row(k) = (X.transpose() * tab.geometry.values.row(q).transpose()).transpose();
            const double area = N.norm();
            // Reference triangle (s, t) has area 1/2 and rule weights sum to 1/2:
            // ds = |N| ds_ref.
            out.ds_w[k] = area * rule.weights[q];
            const Eigen::Vector3d normal =
                area > 0 ? Eigen::Vector3d(N / area) : Eigen::Vector3d::Zero();
            out.normal.row(k) = normal.transpose();
            out.face[k] = f;
            out.cell[k] = cell;
            out.basis_row[k] = j * nq + q;
            if (with_gradients) out.gradients[std::size_t(k)] = tab.space.gradients[q] * Jinv;
          }
        }
      });
  return out;
}

std::vector<char> evaluate_at_face_points(
    const FacePoints& points, const std::function<bool(const Eigen::Vector3d&)>& where,
    const std::function<void(int k, const Eigen::Vector3d& x)>& evaluate) {
  std::vector<char> used(std::size_t(points.size()), 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, points.size(), 64),
                    [&](const tbb::blocked_range<int>& range) {
                      for (int k = range.begin(); k < range.end(); ++k) {
                        const Eigen::Vector3d x = points.x.row(k).transpose();
                        if (where && !where(x)) continue;
                        used[std::size_t(k)] = 1;
                        evaluate(k, x);
                      }
                    });
  return used;
}

void for_each_face_point(const LagrangeMesh& mesh, const FunctionSpace& space,
                         const std::vector<char>& selected, int degree,
                         const std::function<void(int, int, const FacePoint&)>& visit) {
  const FacePoints points = face_points(mesh, space, selected, degree);
  for (int k = 0; k < points.size(); ++k) visit(points.face[k], points.cell[k], points.point(k));
}

}  // namespace curvefem::fem
