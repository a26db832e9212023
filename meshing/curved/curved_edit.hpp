// Connectivity edits of a stitched order-k tet mesh (issue 21's quality stage): edge collapses
// and 2-3 / 3-2 / 4-4 flips of curved tets, on the editing engine (editing/tet_mesh.hpp), driven
// by the curved AMIPS energy of optimize.hpp and certified like the smoothing.
//
// What is kept: every node of the frozen surface (the curved boundary, or with an exterior the
// curved interface) and every face of the mesh boundary, so the boundary and the boundary map do
// not change; the slab layer need not keep its prism structure. An operation replaces a cavity
// of cells by new cells with the same cavity boundary. Nodes on that boundary keep their
// positions (they are shared with the cells around the cavity); a node strictly inside it is
// placed by the slab rule generalised (slab_nodes.hpp): its linear point plus, for each curved
// simplex σ (a face or an edge of the frozen surface) spanned by the node's corners, t · d_σ(λ
// restricted to σ, normalised), t = the node's share of σ's corners and d_σ the patch displacement
// — as a Boolean sum: faces count once, an edge 1 minus the number of those faces holding it. The
// rule only depends on the node's own multiset of corners, so neighbouring cells agree on every
// node; with one curved face it is the stitching's full-shear slab rule.
//
// An operation is kept only if every new cell is certified positive (certify_tet_jacobian), the
// worst energy of the new cells is below the worst energy of the cells they replace, and their
// worst sampled scaled Jacobian (min_scaled_jacobian) is not below that of the replaced cells, so
// certified meshes stay certified and the worst cell of a cavity only gets better. The edits run on
// one thread (deterministic).
#pragma once

#include <vector>

#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/progress.hpp"

namespace curvefem::meshing::curved {

struct CurvedEditOptions {
  int passes = 2;  // rounds of (collapses, flips); 0: off
  // Cells above this mean energy (optimize.hpp cell_energy) are targets. 2 (was 4): at K = 4 the
  // mean curved MIPS of knight fell 51.1 -> 40.7, spot 46.5 -> 39.7, fandisk 46.4 -> 44.9, bunny
  // 52.3 -> 51.5 (benchmarks/results/robustness_mean.md).
  double energy = 2.0;
  bool collapses = true;
  // Target cells whose sampled scaled Jacobian is below this also try to collapse each free
  // corner toward every vertex of its one-ring, not only along the cell's own edges (a flat slab
  // cell's inner corner toward a deeper neighbour); 0: off. Off by default: measured at 0.05 on
  // 10 dev meshes (benchmarks/results/robustness_quality.md) it removed 15-40% of the tets and was
  // mixed (elephant K = 4 better, hinge K = 4 max MIPS 1.9e4 -> 5.0e4, shape_occt K = 4 worse).
  double ring_collapse_scaled_jacobian = 0.0;
  // Every operation, not only splits, must not raise the cavity's worst curved MIPS (the quality
  // goal's measure; the conformal energy weighs a curved dip less).
  bool mips_guard = true;
  // > 0: an operation may not create a locked cell — all four corners fixed (on the curved
  // surface or on a boundary face), so the smoothing after the edits moves none of them — with a
  // curved MIPS above this, unless a locked cell of the cavity was worse already. Without it
  // (CGAL's turbine.off, K = 3): the stitched mesh had no locked cell, the edits left 93, 16 of
  // them above 1e3 and one at 5.0e5 (two boundary faces on a straight feature chain), which the
  // smoothing could not touch, where the smoothing alone had reached 1.3e4. 1e4 (the quality
  // goal's bound) rather than 1e3: measured on 92 runs (benchmarks/results/robustness_locked.md),
  // 1e3 changed 43 of them and met the goal on 78 (79 without); 1e4 changes 20, meets it on 79,
  // never lowers a min scaled Jacobian. 0: off.
  double locked_mips = 1e4;
  bool flips = true;
  // Edge splits of flat cells (after the flips of each pass): an edge of a target cell whose
  // sampled scaled Jacobian is below split_scaled_jacobian, not on the mesh boundary nor on the
  // frozen surface, gets a new corner placed where the worst energy of the new cells' straight
  // tets is lowest (pattern search from the edge's midpoint on its curve), kept under the checks
  // of every operation and two more, since it adds cells: the cavity's worst scaled Jacobian must
  // rise by half (×1.5) and its worst curved MIPS must not grow. A split alone cannot unflatten
  // the flat cell's own children (each keeps a face of it); what it gives is a vertex the later
  // flips, collapses and the smoothing can use where all four corners were fixed.
  // Off by default: measured on the dev meshes (meshing/curved/README.md, step 8) it helps the
  // CAD parts a little and doubles the edits' time.
  bool splits = false;
  double split_scaled_jacobian = 0.01;
  // A refused collapse is replayed while none of the cells it read changed (the same result,
  // fewer checks; curved_edit.cpp CurvedEditMesh::replay); false runs every check.
  bool replay_refusals = true;
  // A collapse's energy check (the first check, which most collapses fail) runs before the
  // editing engine carries the collapse out, on the same new cells built by the same code, so
  // the link condition and the engine's replacement and rollback are skipped where it refuses;
  // false runs it after (the same meshes; kept to test that).
  bool precheck_collapse_energy = true;
  // At most this share of the cells at the start of a pass is split in that pass.
  double max_split_share = 0.2;
  // Last, a flip pass for the mean: 2-3 / 3-2 / 4-4 flips around cells whose curved MIPS is above
  // mean_mips_above, kept when they lower the cavity's summed curved MIPS less c per cell (c the
  // mesh's mean at the start of the pass: so the mesh's mean falls) by 1% of its sum at least,
  // with no new cell's MIPS above max(the cavity's worst, mean_mips_above), no new cell's sampled
  // scaled Jacobian below min(the cavity's smallest, mean_sj_floor), and the other checks above
  // (certificate, locked cells). Each kept flip lowers Σ(MIPS − c) over a finite set of
  // triangulations, so the pass ends. The curved mesher runs it alone, last of all (after the
  // search for the worst cells), so it cannot lower the mesh's smallest scaled Jacobian below
  // min(its value, mean_sj_floor) nor raise its worst MIPS above max(its value, the threshold).
  // Measured at K = 4 (benchmarks/results/robustness_mean_flips.md): mean curved MIPS
  // knight 39.1 -> 37.1, spot 33.5 -> 31.8, bunny 52.6 -> 51.2, fandisk 44.9 -> 42.7 (bichon's
  // P4: 47.9, 56.0, 52.4, 40.5), worst cells unchanged, edits +0.1-0.5 s.
  bool mean_flips = true;
  double mean_mips_above = 30;
  double mean_sj_floor = 0.1;
  // Nor may a flip leave more cells below this scaled Jacobian than it replaced (the quality
  // goal's count of tets below 0.01): without it a cavity holding one such cell was replaced by
  // several, 1-8 more on six knife-disc runs of the corpus (robustness_mean_flips.md).
  double mean_flat = 0.01;
};

struct CurvedEditStats {
  int passes = 0;
  long long collapses = 0, flips = 0, splits = 0;
  long long mean_flips = 0;  // CurvedEditOptions::mean_flips (not counted in flips)
  double mean_mips_before = 0, mean_mips_after = 0;  // the mean pass's, where it ran
  long long attempted = 0;             // operations the engine carried out before the checks
  long long rejected_certificate = 0;  // a new cell not certified positive
  long long rejected_energy = 0;       // the worst energy did not drop, or the scaled Jacobian did
  long long rejected_topology = 0;     // link condition, boundary, existing edge or face
  long long rejected_locked = 0;       // of rejected_energy: a locked cell above locked_mips
  // Refused collapses replayed, counted again in rejected_* (and in attempted, except those
  // refused for their topology, which the engine refuses before the checks).
  long long replayed = 0;
  // Collapses refused by their energy before the engine carried them out
  // (CurvedEditOptions::precheck_collapse_energy), counted in attempted and rejected_energy too.
  long long energy_prechecked = 0;
  int cells_before = 0, cells_after = 0;
  int targets_before = 0, targets_after = 0;  // cells above `energy`
  double max_energy_before = 0, max_energy_after = 0;
  double mean_energy_before = 0, mean_energy_after = 0;
  double seconds = 0;
};

struct CurvedEditResult {
  CurvedEditStats stats;
  // New id of every node of the input mesh (-1: no longer used); frozen nodes always keep one.
  std::vector<int> node_map;
};

/// `total` followed by the run `next` on the same mesh: counts and seconds add, the "after"
/// values are next's, the "before" values stay total's.
void accumulate(CurvedEditStats& total, const CurvedEditStats& next);

/// Edits `mesh` (order-k tets, every cell certified positive) in place. `frozen`: per node, 1 for
/// the nodes that must not move or disappear (the curved surface); the nodes of boundary faces
/// are kept too. Nodes are renumbered (result.node_map); cell_tags follow the cells they came
/// from. Throws MeshingError if the mesh is not conforming (two nodes for one lattice point).
CurvedEditResult edit_curved_mesh(LagrangeMesh& mesh, const std::vector<char>& frozen,
                                  const CurvedEditOptions& options = {},
                                  const ProgressFn& progress = {});

}  // namespace curvefem::meshing::curved
