#include "meshing/core/boundary_map.hpp"

#include <cmath>
#include <string>

#include "meshing/core/error.hpp"

namespace curvefem {

double BoundaryMap::eps_scale_at(int t, const Eigen::Vector3d& w,
                                 const Eigen::MatrixXi& input_faces) const {
  if (eps_scale.empty()) return 1.0;
  double s = 0;
  for (int c = 0; c < 3; ++c) s += w[c] * eps_scale[std::size_t(input_faces(t, c))];
  return s;
}

Eigen::Vector3d BoundaryMap::image(int v) const {
  const int f = vertex_face[v];
  CF_VERIFY(f >= 0, "boundary map: vertex " + std::to_string(v) + " has no image");
  return boundary.map(f, Eigen::Vector3d(vertex_uv(v, 0), vertex_uv(v, 1), 0.0));
}

Eigen::Vector3d BoundaryMap::point_image(int i) const {
  return boundary.map(point_face[i], Eigen::Vector3d(point_uv(i, 0), point_uv(i, 1), 0.0));
}

void validate_structure(const BoundaryMap& map, double tol) {
  if (map.boundary.kind != CellKind::triangle)
    throw InputError("boundary map: the boundary must be made of triangles");
  validate_structure(map.boundary, "boundary map");
  if (map.boundary_node_to_volume.size() != 0 &&
      map.boundary_node_to_volume.size() != map.boundary.num_nodes())
    throw InputError("boundary map: " + std::to_string(map.boundary_node_to_volume.size()) +
                     " volume node ids for " + std::to_string(map.boundary.num_nodes()) +
                     " boundary nodes");
  if (map.vertex_uv.rows() != map.vertex_face.size() || map.vertex_uv.cols() != 2)
    throw InputError("boundary map: vertex coordinates must be #vertices x 2");
  const Eigen::Index np = map.point_face.size();
  if (map.point_input_face.size() != np || map.point_bary.rows() != np ||
      map.point_uv.rows() != np ||
      (np > 0 && (map.point_bary.cols() != 3 || map.point_uv.cols() != 2)))
    throw InputError("boundary map: distance point arrays differ in size");
  for (int i = 0; i < int(np); ++i) {
    const int f = map.point_face[i];
    if (f < 0 || f >= map.boundary.num_cells())
      throw InputError("boundary map: distance point " + std::to_string(i) + ": face id " +
                       std::to_string(f) + " out of range");
    const double a = map.point_uv(i, 0), b = map.point_uv(i, 1);
    const Eigen::Vector3d w = map.point_bary.row(i);
    if (!std::isfinite(a) || !std::isfinite(b) || a < -tol || b < -tol || a + b > 1 + tol ||
        !w.allFinite() || w.minCoeff() < -tol || std::abs(w.sum() - 1) > tol)
      throw InputError("boundary map: distance point " + std::to_string(i) +
                       ": coordinates outside the reference triangle");
  }
  for (int v = 0; v < map.num_input_vertices(); ++v) {
    const int f = map.vertex_face[v];
    if (f < -1 || f >= map.boundary.num_cells())
      throw InputError("boundary map: face id " + std::to_string(f) + " out of range",
                       {.vertex = v});
    if (f < 0) continue;
    const double a = map.vertex_uv(v, 0), b = map.vertex_uv(v, 1);
    if (!std::isfinite(a) || !std::isfinite(b) || a < -tol || b < -tol || a + b > 1 + tol)
      throw InputError("boundary map: coordinates (" + std::to_string(a) + ", " +
                           std::to_string(b) + ") outside the reference triangle",
                       {.vertex = v});
  }
}

}  // namespace curvefem
