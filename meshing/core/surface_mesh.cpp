#include "meshing/core/surface_mesh.hpp"

#include <Eigen/Geometry>

namespace curvefem {

double bbox_longest_edge(const Eigen::MatrixXd& V) {
  if (V.rows() == 0) return 0.0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).maxCoeff();
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> padded_bounding_box(const Eigen::MatrixXd& V,
                                                                double padding_rel) {
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(padding_rel * bbox_longest_edge(V));
  return {V.colwise().minCoeff().transpose() - pad, V.colwise().maxCoeff().transpose() + pad};
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
