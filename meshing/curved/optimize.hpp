// Quality optimization of a curved tet mesh with its boundary frozen: vertex smoothing of every
// corner vertex that is not on the boundary, under certified positivity.
//
// Moving a corner x_v by Δ moves every node of its star by λ_v(node)·Δ (λ_v the barycentric
// weight of v at the node's lattice point), so straight tets stay straight and the curved
// displacement of a slab tet's nodes is kept. The geometric map of each star cell then changes
// by λ_v(ξ)·Δ and its Jacobian by Δ ⊗ ∇λ_v — a rank-one update, which makes the energy and its
// gradient cheap.
//
// Then single high-order nodes off the boundary move on their own (edge, face and cell nodes of
// stars that hold a curved cell): dJ = Δ ⊗ ∇N_n, rank one again. This is what reaches a slab
// tet whose straight shape is fine but whose curved map dips: its corners cannot move the bend,
// its inner nodes can. A node moves only if one of its cells is curved already, so straight
// parts of the mesh stay straight.
//
// Energy of a cell: the mean over the order-k lattice points of the conformal AMIPS energy
// tr(JᵀJ) / (3 det(J)^(2/3)) with J measured against the REGULAR tet (1 for a regular straight
// tet, +∞ when det J ≤ 0). A move is accepted only if every cell of the star is certified
// positive (certify_tet_jacobian) and the worst energy of the star does not grow, so a mesh
// whose tets are all certified stays certified and, its boundary untouched, stays an embedding.
#pragma once

#include <vector>

#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/progress.hpp"
#include "meshing/curved/curved_edit.hpp"

namespace curvefem::meshing::curved {

struct OptimizeOptions {
  int sweeps = 8;           // passes over the vertices whose star changed
  int iterations = 4;       // gradient steps per vertex visit
  double tolerance = 1e-3;  // a visit stops when the star energy drops by less (relative)
  bool flips = true;        // 2-3 / 3-2 / 4-4 flips of the straight interior first (tet_flips)
  // Then single high-order nodes (edge, face and cell nodes off the boundary) of stars holding a
  // curved cell with a sample whose energy exceeds node_energy; 0 sweeps: off. A node move must
  // lower the star's energy, raise no sample's, and not raise the star's Jacobian variation
  // Σ mean|J − J̄|²/|J̄|² (a discrete |D²F|): without that last guard the FEM error on the moved
  // maps rose (geometry-order matrix, feature cylinder, k = p = 3 elasticity L2 4.0e-3 -> 2.0e-2)
  // while the energy fell; with it the matrix's errors move by < 1.5%. Measured at K = 4:
  // bunny min scaled Jacobian 9.8e-4 -> 1.2e-3, fandisk 3.0e-3 -> 1.0e-2 (meshing/curved/README).
  int node_sweeps = 4;
  double node_energy = 10;
  // Stars with a sample above this energy (near-degenerate cells) skip the variation guard:
  // there conditioning matters more than the map's smoothness (knight, K = 4: min scaled
  // Jacobian 5.3e-4 with the guard everywhere, 6.7e-3 with it lifted above 50; the geometry-order
  // matrix has no such cells and its errors are unchanged).
  double node_free_energy = 50;
  // A move may not take the star's worst sampled scaled Jacobian (min_scaled_jacobian) below
  // min(its value before, this floor): the energy alone let moves create the mesh's worst cells.
  double scaled_jacobian_floor = 0.05;
  // Nor take the star's worst curved MIPS (curved_mips, the quality goal's measure) above
  // max(its value before, this ceiling); 0: off. The conformal energy above is a mean over the
  // lattice and weighs a dip of the curved map less, so without this moves raised the mesh's
  // worst curved MIPS (cylinder_sharp K = 3 with the edits' MIPS guard: 1.0e3 -> 4.7e3). A move
  // that raises the star's worst scaled Jacobian is exempt (capped too, abc_00000008's worst
  // cell fell 3.3e-4 -> 5.8e-5). benchmarks/results/robustness_quality.md.
  double mips_ceiling = 1000;
  // Last, a search for the worst cells: every free corner in the star of a cell whose sampled
  // scaled Jacobian is below worst_scaled_jacobian, and every free high-order node of such a
  // star that holds a curved cell, moves to RAISE THE STAR'S MINIMUM scaled Jacobian (a compass
  // search over 14 directions, steps halved from a quarter of its edges or lattice spacing),
  // under the certificate, without raising the star's summed curved MIPS, nor its worst above
  // max(its value before, mips_ceiling). The energy above is a sum, and conformal AMIPS grows
  // only like t^(-2/3) as a cell flattens: a sum-descent left cheese's flattest slab tet
  // (an interior corner in the plane of a boundary face across a reflex edge) at 1.1e-5 while
  // one move of that corner lifts its star to 0.05. Nor may a move add star cells below
  // worst_flat (the share of tets below 0.01 is part of issue 21's quality goal: on the knife
  // discs a raised minimum pushed its neighbours under 0.01, 415 -> 427 of 1,273 tets).
  // 0 sweeps: off.
  int worst_sweeps = 3;
  double worst_scaled_jacobian = 0.02;
  double worst_flat = 0.01;
  // Then, with worst_mips > 0, the same search for stars holding a cell whose curved MIPS is
  // above worst_mips: it lowers the star's worst curved MIPS (by 5% at least), keeps every cell's
  // scaled Jacobian above min(the star's before, worst_scaled_jacobian), and the other guards
  // above. A near-flat cell can be far above the quality goal's MIPS (1e4) with a sampled scaled
  // Jacobian above worst_scaled_jacobian (thin_plate_05, K = 3: 1.03e4 at 0.027), which the
  // search by scaled Jacobian never visits. Measured at 2000 without a visit budget on 38 dev
  // and 72 corpus runs (benchmarks/results/robustness_worst_mips.md): max curved MIPS lower on
  // 24, higher on none; quality goal 80 -> 81; min scaled Jacobian lowered on 8 runs, each only
  // to the 0.02 floor. 0: off.
  double worst_mips = 2000;
  // At most this many stars per sweep of that search, the worst first (0: all). Where thousands
  // of stars hold such cells (knife discs, tr12j_occt) visiting all of them cost 10-30 s for a
  // few per cent; with 100, tr12j_occt K = 4's optimize stage is 30.7 s (30.3 s without the
  // search, 50.7 s visiting all).
  int worst_mips_visits = 100;
  // In that search, where the star's worst cell is above worst_mips_slack_above (the quality
  // goal's 1e4), the star's smallest scaled Jacobian may fall by this fraction (never below
  // min(its value before, 2e-3), twice the goal's 1e-3). Where the star's minimum sits on a curved
  // cell at its own optimum, keeping it strictly refused every move: cgal_dino K = 3, the vertex
  // under the one cell of curved MIPS 1.67e4 — a move of 0.011 gives 4.9e3 (straight-tet estimate),
  // but costs a curved neighbour 0.0065 -> 0.006 of its scaled Jacobian. 0: the minimum may not
  // fall.
  double worst_mips_sj_slack = 0.1;
  // Applied to every star above worst_mips instead, the slack lowered the min scaled Jacobian of
  // 14 dev and corpus runs (knight_decimated K = 4 0.020 -> 0.016) for max MIPS already below
  // the goal.
  double worst_mips_slack_above = 1e4;
  // Last, the same search lowering the star's SUMMED curved MIPS by 1% at least, for stars
  // holding a cell above mean_mips_above, under the per-cell guards below (and the other guards
  // above): the mean, without trading any cell's shape for it. Corners and the high-order nodes
  // of curved stars move, as in the worst-cell search; a trial's MIPS is a rank-one update of
  // each cell's Jacobians at curved_mips' samples. 0 sweeps (the default): off. Measured at K = 4
  // with 2 sweeps (benchmarks/results/robustness_mean_polish.md): WITHOUT the maps' guards
  // (mean_variation_guard false) the mean falls 11-15% (bunny 52.6 -> 45.0, fandisk 44.9 -> 37.4;
  // bichon's P4 52.4 and 40.5), but by bending the maps: the FEM error on them rose up to 20x.
  // With them, 2-3% (bunny 51.0, fandisk 43.7) for 2-9 s more of the optimize stage.
  int mean_sweeps = 0;
  double mean_mips_above = 50;
  // Each cell of the star keeps its own guard (not only the star's worst): its sampled scaled
  // Jacobian may not fall below min(its value before, mean_sj_floor), nor its curved MIPS rise
  // above max(its value before, mean_mips_above).
  double mean_sj_floor = 0.1;
  // The maps' guards: a single high-order node's move may not raise any star cell's Jacobian
  // variation Σ|J − J̄|²/|J̄|² over curved_mips' samples (as in the node phase), nor its
  // distortion d2 or d3 (element_distortion.hpp). Without them the polish bought most of its fall
  // of the mean with the maps' higher derivatives, and the FEM error on them rose: the geometry
  // matrix (tests/mapping/test_geometry_matrix.cpp) at k = 4, p = 3, cylinder Poisson L2 3.5e-3
  // -> 2.1e-2 and elasticity 7.4e-3 -> 1.5e-1; with them 3.6e-3 and 8.6e-3, the other entries
  // within 3%. (Corner moves add an affine field per cell: D²F and D³F stay.)
  bool mean_variation_guard = true;
  int mean_evaluations = 100;  // trial positions per visit at most
  // Collapses and flips of the stitched curved mesh before the smoothing (curved_edit.hpp; run by
  // the curved mesher, not by optimize_vertices).
  CurvedEditOptions edits;
};

struct OptimizeStats {
  int movable_vertices = 0;
  int sweeps = 0;
  long long visits = 0, moves = 0, rejected_by_certificate = 0;  // rejected: both phases
  int movable_nodes = 0, node_sweeps = 0;
  // The search for the worst cells: corners and nodes in their stars, sweeps, visits, moves, and
  // the lowest sampled scaled Jacobian over those stars before and after (1 when there were none).
  int worst_movable = 0, worst_sweeps = 0;
  long long worst_visits = 0, worst_moves = 0;
  double worst_sj_before = 1, worst_sj_after = 1;
  int worst_mips_movable = 0;  // OptimizeOptions::worst_mips
  long long worst_mips_visits = 0, worst_mips_moves = 0;
  double worst_mips_before = 0, worst_mips_after = 0;  // the mesh's worst curved MIPS
  int mean_mips_movable = 0;                           // OptimizeOptions::mean_sweeps
  long long mean_mips_visits = 0, mean_mips_moves = 0;
  double mean_mips_before = 0, mean_mips_after = 0;  // the mesh's mean curved MIPS
  bool mean_variation_guard = false;                 // that polish ran with it
  double worst_seconds = 0;
  long long node_visits = 0, node_moves = 0;
  double max_energy_before = 0, max_energy_after = 0;
  double mean_energy_before = 0, mean_energy_after = 0;
  double seconds = 0;
  // Flips of the straight fills before the smoothing (set by the curved mesher; energies of the
  // straight tets only, means weighted by tet count over the interior and exterior fills).
  struct Flips {
    long long count = 0, tets_before = 0, tets_after = 0;
    double max_energy_before = 0, max_energy_after = 0;
    double mean_energy_before = 0, mean_energy_after = 0;
    double seconds = 0;
  } flips;
  CurvedEditStats edits;  // set by the curved mesher
};

/// Energy of one cell as defined above (order from the node count).
double cell_energy(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes);

/// Smooths the free corner vertices of a tetrahedral LagrangeMesh in place: corners that are not
/// on the mesh boundary and not flagged in `frozen` (per node; may be null). Cells must already
/// be certified positive (a cell that is not keeps its vertices: its star never improves).
OptimizeStats optimize_vertices(LagrangeMesh& mesh, const OptimizeOptions& options = {},
                                const ProgressFn& progress = {},
                                const std::vector<char>* frozen = nullptr);

}  // namespace curvefem::meshing::curved
