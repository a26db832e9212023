#include "meshing/core/surface_mesh.hpp"

#include <Eigen/Geometry>

namespace curvefem {

double bbox_longest_edge(const Eigen::MatrixXd& V) {
  if (V.rows() == 0) return 0.0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).maxCoeff();
}

double signed_volume(const SurfaceMesh& mesh) {
  if (mesh.V.rows() == 0) return 0.0;
  const Eigen::RowVector3d c = mesh.V.colwise().mean();  // reduces cancellation
  double vol = 0.0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = (mesh.V.row(mesh.F(f, 0)) - c).transpose();
    const Eigen::Vector3d b = (mesh.V.row(mesh.F(f, 1)) - c).transpose();
    const Eigen::Vector3d d = (mesh.V.row(mesh.F(f, 2)) - c).transpose();
    vol += a.dot(b.cross(d));
  }
  return vol / 6.0;
}

}  // namespace curvefem
