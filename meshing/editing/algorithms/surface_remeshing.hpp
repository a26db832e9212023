#pragma once
// Surface remeshing algorithms written on the editing framework (thesis §6.3):
//   shortest-edge collapse [Hoppe 1996], QSlim [Garland & Heckbert 1997], isotropic remeshing
//   [Botsch & Kobbelt 2004], each optionally constrained to an envelope of the input.
//
// Input: a manifold, consistently oriented triangle surface (boundary vertices are frozen).
// Every operation is rejected if it folds a face (a new face normal opposite the face it came
// from), creates a degenerate face, or — with `envelope` > 0 — leaves the ε-envelope of the
// input. The envelope test is conservative: a new triangle with longest edge L is sampled on a
// barycentric grid with n = ceil(2L / (√3 ε)) subdivisions; every point of the triangle is within
// r = L / (n√3) <= ε/2 of a sample (the covering radius of a triangle of longest edge ℓ is at most
// ℓ/√3), so requiring distance(sample, input) <= ε - r at every sample proves the whole triangle
// lies within ε of the input (distance to a set is 1-Lipschitz).

#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/editing/scheduler.hpp"

namespace curvefem::meshing::editing {

enum class RemeshAlgorithm { shortest_collapse, qslim, isotropic };

struct RemeshOptions {
  RemeshAlgorithm algorithm = RemeshAlgorithm::shortest_collapse;
  std::size_t target_faces = 0;  // shortest_collapse, qslim: stop at or below this face count
  double target_edge = 0;        // isotropic: target edge length (absolute)
  double envelope = 0;           // ε (absolute); 0 disables the envelope
  int threads = 1;
  int iterations = 5;  // isotropic: split/collapse/swap/smooth rounds
};

struct RemeshResult {
  SurfaceMesh mesh;
  std::vector<std::pair<std::string, PassStats>> passes;  // one entry per scheduler pass
  double seconds = 0;
};

// Throws InputError for a non-manifold or inconsistently oriented input.
RemeshResult remesh(const SurfaceMesh& input, const RemeshOptions& options);

struct SurfaceQuality {
  std::size_t vertices = 0, faces = 0;
  double min_angle_deg = 0, max_angle_deg = 0;
  double min_edge = 0, mean_edge = 0, max_edge = 0;
  std::map<int, std::size_t> valence_histogram;
  // Largest distance from the surface (vertices and face samples) to `reference`, and from the
  // reference's vertices to the surface (a one-sided Hausdorff estimate each way).
  double max_deviation = 0;
  double max_deviation_from_reference = 0;
};

SurfaceQuality measure_quality(const SurfaceMesh& surface, const SurfaceMesh& reference);

}  // namespace curvefem::meshing::editing
