#pragma once
// Harmonic triangulations [Alexa 2019] on the editing framework (thesis §6.3): starting from the
// Delaunay tetrahedralization of a point set (CGAL), apply 2-3, 3-2 and 4-4 flips that lower the
// sum of the harmonic indices of the tets they replace, keeping every tet positively oriented
// (exact orientation predicate). The harmonic index of a tet is the trace of its P1 stiffness
// matrix, h(t) = Σ_faces A_f² / (9 V); it is large for slivers, so lowering it removes them.

#include <Eigen/Core>
#include <vector>

#include "meshing/editing/scheduler.hpp"

namespace curvefem::meshing::editing {

struct HarmonicOptions {
  int threads = 1;
};

struct TetQuality {
  std::size_t tets = 0;
  double mean_harmonic_index = 0;  // mean h(t), divided by the mean edge length (scale-free)
  double max_harmonic_index = 0;   // same normalization
  double min_dihedral_deg = 0;
  std::size_t slivers = 0;  // tets with a dihedral angle below 10 degrees
  double volume = 0;
};

struct HarmonicResult {
  Eigen::MatrixXd V;  // #V x 3
  Eigen::MatrixXi T;  // #T x 4, positively oriented
  TetQuality before, after;
  std::vector<std::pair<std::string, PassStats>> passes;
  double delaunay_seconds = 0, seconds = 0;
};

// points: #P x 3 (distinct).
HarmonicResult harmonic_triangulation(const Eigen::MatrixXd& points,
                                      const HarmonicOptions& options);

TetQuality measure_tets(const Eigen::MatrixXd& V, const Eigen::MatrixXi& T);

}  // namespace curvefem::meshing::editing
