// Where a curved mesh's worst elements come from the input itself (issue 21): input features that
// `curvefem check` warns of (check::CheckReport::warnings) and that the coarse boundary kept as
// they are, so every tet on them is as flat as they are whatever the optimization does.
//   needle faces     input faces with a corner angle below CheckOptions::needle_angle_deg, kept
//                    as a boundary face (its three corners are boundary corners at the same
//                    points, and a boundary face joins them);
//   near-fold edges  input edges whose face normals turn by more than fold_angle_deg, kept as a
//                    boundary edge.
// The tets on a kept needle face, and around a kept fold edge, are compared with the mesh's worst
// (the independent validation's per-tet curved MIPS and scaled Jacobian). Seen on unseen scans
// (benchmarks/results/robustness_input_floors.md): CGAL's hand.off keeps a fold of 2.1° (normal
// turn 177.9°) whose slab tet has curved MIPS 4.4e6; femur.off keeps a needle of 0.63°.
#pragma once

#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "meshing/check/check_surface.hpp"
#include "meshing/core/boundary_map.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::pipeline {

struct InputFloors {
  int needle_faces = 0, needle_faces_kept = 0;
  int near_fold_edges = 0, near_fold_edges_kept = 0;
  int tets_at_kept = 0;  ///< tets on a kept needle face or holding a kept fold edge
  double max_mips_at_kept = 0, min_scaled_jacobian_at_kept = HUGE_VAL;
  /// The mesh's tet of largest curved MIPS (and, separately, of smallest scaled Jacobian) is one
  /// of tets_at_kept.
  bool worst_mips_tet_at_kept = false, worst_scaled_jacobian_tet_at_kept = false;
  /// The shortest input edge of a kept needle face or kept fold edge (0: none kept), and it over
  /// the bbox's longest edge: below ε, `curvefem mesh --merge-short-edges` can remove the floor
  /// (check/merge_short_edges.hpp; CGAL's femur: 1e-4, hand: 3e-3).
  double shortest_edge_at_kept = 0, shortest_edge_at_kept_rel = 0;
  std::vector<int> kept_needle_faces;               ///< input face ids (up to 10)
  std::vector<std::array<int, 2>> kept_fold_edges;  ///< input vertex pairs (up to 10)
};

/// `mesh` (order-k tets) with its boundary map `map` on `input`; cell_mips and
/// cell_scaled_jacobian per tet of `mesh` (CurvedValidation's). An exterior mesh's boundary faces
/// that are not in `map` are ignored.
InputFloors input_floors(const SurfaceMesh& input, const BoundaryMap& map, const LagrangeMesh& mesh,
                         const std::vector<double>& cell_mips,
                         const std::vector<double>& cell_scaled_jacobian,
                         const check::CheckOptions& options = {});

nlohmann::json input_floors_json(const InputFloors& floors,
                                 const check::CheckOptions& options = {});

/// Where the mesh's worst tet is on a kept needle or fold whose shortest edge is below `eps_rel`
/// (relative to the bbox): a one-line hint naming `--merge-short-edges` with a length just above
/// that edge; empty otherwise.
std::string merge_hint(const InputFloors& floors, double eps_rel);

}  // namespace curvefem::pipeline
