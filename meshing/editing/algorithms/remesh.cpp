#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <numbers>

#include "meshing/core/error.hpp"
#include "meshing/editing/algorithms/surface_passes.hpp"
#include "meshing/editing/algorithms/surface_remeshing.hpp"

namespace curvefem::meshing::editing {

RemeshResult remesh(const SurfaceMesh& input, const RemeshOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<SurfaceEditMesh> mesh;
  switch (options.algorithm) {
    case RemeshAlgorithm::shortest_collapse:
      mesh = make_shortest_collapse_mesh();
      break;
    case RemeshAlgorithm::qslim:
      mesh = make_qslim_mesh();
      break;
    case RemeshAlgorithm::isotropic:
      mesh = make_isotropic_mesh();
      break;
  }
  if (options.algorithm == RemeshAlgorithm::isotropic) {
    if (!(options.target_edge > 0))
      throw InputError("isotropic remeshing needs a positive target edge length");
  } else if (options.target_faces == 0) {
    throw InputError("collapse algorithms need a positive target face count");
  }
  if (options.envelope < 0) throw InputError("the envelope must be non-negative");
  mesh->load(input);
  std::unique_ptr<SurfaceDistance> distance;
  if (options.envelope > 0 || options.algorithm == RemeshAlgorithm::isotropic)
    distance = std::make_unique<SurfaceDistance>(input.V, input.F);
  if (options.envelope > 0) {
    mesh->envelope = distance.get();
    mesh->envelope_eps = options.envelope;
  }
  RemeshResult result;
  switch (options.algorithm) {
    case RemeshAlgorithm::shortest_collapse:
      shortest_edge_collapse(*mesh, options.target_faces, options.threads, result.passes);
      break;
    case RemeshAlgorithm::qslim:
      qslim(*mesh, options.target_faces, options.threads, result.passes);
      break;
    case RemeshAlgorithm::isotropic:
      isotropic_remeshing(*mesh, *distance, options.target_edge, options.iterations,
                          options.threads, result.passes);
      break;
  }
  result.mesh = mesh->extract();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

SurfaceQuality measure_quality(const SurfaceMesh& s, const SurfaceMesh& reference) {
  SurfaceQuality q;
  q.vertices = std::size_t(s.num_vertices());
  q.faces = std::size_t(s.num_faces());
  if (s.num_faces() == 0) return q;
  q.min_angle_deg = 180;
  q.min_edge = 1e300;
  double edge_sum = 0;
  std::size_t edge_count = 0;
  std::vector<std::vector<int>> neighbours(std::size_t(s.num_vertices()));
  for (int f = 0; f < s.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = s.V.row(s.F(f, k)), a = s.V.row(s.F(f, (k + 1) % 3)),
                            b = s.V.row(s.F(f, (k + 2) % 3));
      const Eigen::Vector3d u = a - p, w = b - p;
      const double angle = std::atan2(u.cross(w).norm(), u.dot(w)) * 180.0 / std::numbers::pi;
      q.min_angle_deg = std::min(q.min_angle_deg, angle);
      q.max_angle_deg = std::max(q.max_angle_deg, angle);
      const double len = u.norm();
      q.min_edge = std::min(q.min_edge, len);
      q.max_edge = std::max(q.max_edge, len);
      edge_sum += len;
      ++edge_count;
      neighbours[std::size_t(s.F(f, k))].push_back(s.F(f, (k + 1) % 3));
      neighbours[std::size_t(s.F(f, k))].push_back(s.F(f, (k + 2) % 3));
    }
  }
  q.mean_edge = edge_sum / double(edge_count);  // each interior edge counted twice: same mean
  for (auto& n : neighbours) {
    if (n.empty()) continue;
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
    ++q.valence_histogram[int(n.size())];
  }
  // Deviation both ways: surface vertices and face samples to the reference, reference
  // vertices to the surface.
  const SurfaceDistance to_reference(reference.V, reference.F);
  for (int f = 0; f < s.num_faces(); ++f)
    q.max_deviation = std::max(
        q.max_deviation, to_reference.max_distance_sampled(s.V.row(s.F(f, 0)), s.V.row(s.F(f, 1)),
                                                           s.V.row(s.F(f, 2)), 3));
  const SurfaceDistance to_surface(s.V, s.F);
  for (int v = 0; v < reference.num_vertices(); ++v)
    q.max_deviation_from_reference = std::max(
        q.max_deviation_from_reference, std::sqrt(to_surface.squared_distance(reference.V.row(v))));
  return q;
}

}  // namespace curvefem::meshing::editing
