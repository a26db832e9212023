#pragma once
// Coarse curved tetrahedral meshes of order k = 1..4 whose boundary is in bijection with a dense
// input surface (thesis chapter 5; DESIGN.md §1–2; reference-notes §3.8–3.9).
//
// Pipeline:
//   1. shell      the bijective prismatic shell around the input (meshing/shell);
//   2. coarsen    shell simplification under the distance bound: every input vertex x stays in a
//                 prism, at prism coordinates (u, v, h), with |x - mid(u, v)| <= ε for the
//                 *linear* middle triangle, or (curved-aware) within a few ε of it and ε of the
//                 face's fully curved patch; feature corners are frozen;
//   3. curve      the middle surface of every coarse face becomes an order-k Lagrange triangle
//                 whose nodes interpolate the input along the shell's fibers (P_T at the node's
//                 (u, v)); the displacement from the linear triangle is blended per face by
//                 α ∈ {1, 1/2, ..., 0} until the curved slab tets are certified positive and the
//                 ε bound holds at the face's input vertices. α = 0 is the linear shell, valid by
//                 the invariants of steps 1–2, so the search always ends;
//   4. fill       the inside of the shell's bottom surface is tetrahedralized without changing it
//                 (meshing/tetfill, straight tets);
//   5. stitch     each coarse face's bottom half-prism (base → curved middle) becomes 3 order-k
//                 tets of the canonical split (2 at a pinched corner): node = linear point +
//                 h · displacement(u, v), h the node's share of the middle corners; nodes are
//                 shared through the multiset of global corner ids they are built from.
// The boundary is the curved middle surface; φ maps input vertex x to its coarse face at (u, v).
// Every claim is re-checked by validate_curved_mesh (curved_validate.hpp), not trusted here.

#include <Eigen/Core>
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "meshing/core/boundary_map.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/progress.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/curved/optimize.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::meshing::curved {

struct CurvedMeshOptions {
  int order = 3;                // geometric order k, 1..4
  double eps_rel = 1e-2;        // distance bound, relative to the bbox edge
  double thickness_rel = 0.02;  // shell half-thickness cap
  // Initial half-thickness cap per vertex, × its mean input edge length (ShellOptions; 0: off).
  // Measured on the refined elephant (88,928 faces, median edge 0.5% of the bbox), K = 3,
  // ε = 2%: 9,258 coarse faces without it, 662 with 1 (and 674 with 0.5); the dev meshes at
  // ε = 1% change by -5% to +3%.
  double thickness_per_edge = 1.0;
  std::vector<std::array<int, 2>> feature_edges;  // input vertex pairs (validated by the caller)
  // Feature curves smaller than the bound are not kept (0: every given edge is): a connected set
  // of feature edges whose bounding box diagonal is below feature_min_size × ε (the finest
  // level's, times the smallest eps_scale at its vertices) is dropped from feature_edges before
  // anything else (drop_small_feature_components). Such curves — a hole's rim of a fraction of
  // ε, creases where tessellation slivers fold — end in frozen corners (or chains whose snapping
  // folds their tiny faces), so the coarse surface kept edges of their size beside faces of ε's,
  // and the slab tets on them were needles and caps. Callers passing a feature file set it 0.
  double feature_min_size = 2;
  // Open ends of the kept feature curves are cut back by this × ε (the same ε; 0: off, the
  // default) before anything else (trim_feature_ends): a fading crease's end is a frozen corner,
  // and next to another curve it kept a cap in the coarse surface. Off: at 1 on the dev meshes it
  // met the quality goal on 30 of 38 runs (29 off) but two runs fell to min sJ ~1e-5..1e-6
  // (meshing/curved/README.md, step 2). Callers passing a feature file set it 0.
  double feature_end_trim = 0;
  // The distance bound holds at every input vertex, and also at
  //   - constraint points: points on the input surface (within 1e-6 of the bbox edge of it;
  //     InputError otherwise), snapped onto it;
  //   - eps_samples = L >= 2: the points of the degree-L barycentric lattice of every input
  //     triangle that are not its corners (on shared edges once), L = 2 the edge midpoints,
  //     L = 3 two points per edge and the centroid.
  // Enforced by the coarsening and the curving like the input vertices; written into the
  // boundary map (distance_points) and re-checked by the validator.
  std::vector<Eigen::Vector3d> constraint_points;
  int eps_samples = 0;
  // Spatially varying ε (issue 22): empty, or one factor in (0, 1] per input vertex; the bound at
  // input vertex v is eps_rel · eps_scale[v] (bbox-relative), at a point inside an input face the
  // linear interpolation of its corners' bounds. The coarsening, the curving and the validator
  // (through BoundaryMap::eps_scale) all use it.
  std::vector<double> eps_scale;
  int simplify_rounds = 5;
  // Depth of the slab layer below the curved surface, relative to the mean coarse edge length at
  // each vertex (0: keep the shell's base, whose thin slabs make needle tets).
  double slab_depth = 0.4;
  // Once the slab layer is deeper, faces curved below α = 1 try a larger α again (Builder::
  // raise_alpha in curved_mesher.cpp).
  bool recurve = true;
  // Then faces whose slab tets (still without the smoothing) are below this sampled scaled
  // Jacobian try a smaller α, checked like the recurving (certified, within ε), keeping the first
  // that lifts their slabs and their neighbours' to it, or the best if it doubles their worst
  // (Builder::lower_for_quality; 0: off). Off by default: measured at K = 3, ε = 1% (off → 0.01;
  // min scaled Jacobian, tets below 0.01, max curved MIPS) it helps some organic meshes
  // (fertility 6.3e-3 → 9.0e-3, 3 → 1; knight 7.7e-3 → 1.4e-2, 1 → 0) but not where the pinching
  // edge is held curved by a neighbour that needs full curving for ε (homer's worst tet 7.8e-4 →
  // 7.6e-4), and not on CAD parts (anchor 17 → 18 below 0.01, max MIPS 3.5e3 → 4.2e3; hinge min
  // 2.1e-3 → 1.5e-3, 17 → 21 below, max MIPS 2.7e4 → 1.4e4); igea, spot, fandisk unchanged. It
  // judges slabs before the smoothing, which fixes most of them anyway, and costs fidelity
  // (homer: 51 of 726 faces less curved).
  double curve_quality_floor = 0;
  // Then faces whose curved middle triangle is parametrically distorted — its smallest area
  // element below this fraction of its largest, or folded (its normal turned against the linear
  // triangle's) — try a smaller α, checked like the quality floor, keeping the first that reaches
  // the floor or else the least distorted (Builder::lower_for_distortion; 0: off). Such patches
  // come from fibers that cross a noisy or folded input far apart, and make flat boundary tets
  // that no smoothing can lift (noise_sphere_2, K = 3: max curved MIPS 5.8e4 -> 3.5e3).
  // Faces that need full curving for ε keep it.
  double curve_distortion_floor = 0.1;
  // The coarsening's side of it (SimplifyOptions::curved_min_area_ratio): a face that needs full
  // curving for ε cannot be lowered, so its fully curved patch must meet this bound to be made
  // (0: off). Off by default: at 0.1, against the floor alone (27 dev runs and 31 corpus runs
  // measured, benchmarks/results/robustness_distortion.md) it changed the coarse meshes both
  // ways (rocker_arm K = 3 484 -> 690 faces, fandisk 214 -> 176) and the worst cells got worse
  // more often than better (max MIPS higher on 13 dev runs, lower on 6; quality goal unchanged).
  double curved_min_area_ratio = 0;
  // Slab nodes (slab_nodes.hpp): false (default) the full shear t·d of the patch; true the
  // low-degree nodes (the patch's quadratic part at degree 2, the rest sheared), with the shear as
  // a per-face fallback. Measured at K = 3 (issue 20): less cubic content and a lower pure
  // discretization error on the icosphere (P3 2.76e-4 against 3.89e-4), but on the elephant the
  // thickening then left a different mesh and P3 elasticity moved from 0.40% to 0.94% RMS away
  // from a dense P2 reference (3% stiffer); hence off by default.
  bool low_degree_slabs = false;
  // Shape guard of the coarsening (2-D MIPS of the middle triangles, 2 = equilateral; 0: off).
  double max_triangle_mips = 10;
  // SimplifyOptions::shape_slack: where the removed triangles are already worse than
  // max_triangle_mips, the shape guard lets a collapse raise its star's worst MIPS by this factor,
  // so needle strips (CAD cylinders) coarsen instead of reaching the slab as needle tets (0: the
  // strict guard everywhere).
  double shape_slack = 0.02;
  // Thickness guard of the coarsening (SimplifyOptions::max_edge_per_thickness; 0: off): no
  // coarse edge longer than this many times the object's local thickness at its ends, so slab
  // tets in thin parts (plates, knife edges, thin limbs) are not flatter than that.
  double max_edge_per_thickness = 8;
  // Thin-part refinement of the input before the shell (meshing/shell/thin_refine.hpp; 0: off):
  // input edges longer than this many times the local thickness are bisected (same surface), so
  // the guard above has vertices to keep where the input itself is too coarse (a CAD plate).
  // 3 since 2026-12-05 (was 8), with the closure below: at K = 3 the quality goal is met on 22 of
  // 36 corpus runs (8: 20) and 15 of 18 dev runs (8: 15); thin_tube_05 1,026 -> 3 tets below
  // 0.01 (benchmarks/results/robustness_thin_closure.md).
  double thin_refine_ratio = 3;
  // Its longest-edge closure and shape check along kept edges (ThinRefineOptions::
  // longest_edge_closure, max_child_mips); false / 0 give the refinement of before 2026-12-05,
  // which left slivers along CAD edges (kept for tests of the stages after it).
  bool thin_refine_closure = true;
  double thin_refine_child_mips = 20;
  // Shape refinement of the input before the shell (meshing/shell/thin_refine.hpp,
  // refine_poor_shapes; 0: off): input faces with a 2-D MIPS above shape_refine_mips whose
  // longest edge is longer than shape_refine × ε have it bisected, feature edges included (their
  // halves join the feature chains; kept whole when the chains are off), so that CAD
  // tessellations (fans of needles and caps) offer the coarsening vertices inside their flat
  // faces. The fibers then cross the refined surface (Shell::refinement, ShellFibers).
  double shape_refine = 8;
  double shape_refine_mips = 20;
  // ShapeRefineOptions::min_cone_angle in degrees (0: off): faces whose sharpest corner is a cone
  // tip of total face angle below it are spike sides and not bisected. 90 restores the needle
  // spheres and changes none of the 19 dev meshes (meshing/curved/README.md, step 1).
  double shape_refine_spike_angle = 90;
  // After meshing a refined input (the shape or thin refinement bisected anything), φ of every
  // input vertex is pulled back along the coarse shell's fibers, as the boundary map's inverse
  // does. Where that misses the vertex by more than 1e-6 of the bounding box (seen on CGAL's
  // spool.off, an unseen CAD part: 7.4e-3 next to a feature chain, with 8 shape bisections), the
  // input is meshed again without the shape refinement, then without the thin refinement too
  // (CurvedMeshStats::roundtrip_fallback). false: no check (the validator's still runs).
  bool refined_roundtrip_check = true;
  // Construction-time embedding of the curved boundary (issue 21): after the recurving, the
  // curved middle surface is sampled 2K per edge (as the validator does) and the faces of every
  // intersecting pair lower their curving α, down to their linear triangles if need be
  // (CurvedMeshStats::embedding_*). Seen on CGAL's femur.off with --feature-end-trim 1: two
  // neighbouring patches crossing, the validator's 10 intersections and exit 3 (distorted
  // patches: with curve_distortion_floor, the default since, they are lowered before and the
  // boundary is embedded without this repair). false: off.
  bool embed_boundary = true;
  // Between collapse rounds (simplify.hpp): edge flips, pillar rotation toward the coarse
  // surface, and thickness growth up to shell_zoom_rel × the longest bbox edge per half-pillar
  // (0: off), so the coarsening is limited by ε rather than by the initial shell.
  bool shell_flips = true;
  bool shell_rotate = true;
  double shell_zoom_rel = 0.1;
  // SimplifyOptions::section_cos, the coarse shell's distortion bound: every input face a new
  // prism covers makes at least this cosine with its half-pillars (0: the bare section
  // condition, under which a pillar may end tangent to an input face up to rounding and the
  // floating-point map stop being bijective; meshing/shell/README.md).
  double shell_pillar_cos = meshing::shell::k_section_cos;
  // SimplifyOptions::section_cos_relative: where the input's shell already leans further than
  // shell_pillar_cos from an input face (knife edges), this fraction of its own cosine instead.
  double shell_pillar_cos_relative = meshing::shell::k_section_cos_relative;
  // SimplifyOptions::min_reference_area_ratio: a chain collapse may not flatten a face of the
  // reference copy below this fraction of its input area (0: only exactly degenerate faces are
  // refused, as before 2026-12-06; CGAL's part.off then lost vertex 18's round trip by 3.1e-3).
  double chain_min_area_ratio = meshing::shell::k_min_reference_area_ratio;
  // SimplifyOptions::zoom_passes: up to this many doublings a round for pillars pinned below
  // 0.05 of their star's edges (1: one, as every pillar). Off by default: at 4, measured on 38
  // dev and 72 corpus runs (benchmarks/results/robustness_zoom.md), the knife discs' worst cells
  // rose 2-20x and tr12j_occt K = 4's 5x (its 179.9° cap over a 0.016-wide strip went), but
  // cheese fell 8x (3.8e-4 -> 4.8e-5) and thin_plate_05 K = 3 left the quality goal; organic
  // meshes unchanged.
  int shell_zoom_passes = 1;
  // Pan passes (simplify.hpp) and split passes on middle triangles with a 2-D MIPS above
  // shell_split_mips (0: off). Pans at ε = 1%, K = 3 (dev meshes, 1 thread): faces -3% (bunny)
  // to -9% (homer), slab min scaled Jacobian up on knot2 0.0033 -> 0.0094, homer 0.0023 -> 0.0063,
  // down on fandisk 0.015 -> 0.011; time within 10%. Splits lower the slab quality (simplify.hpp).
  bool shell_pan = true;
  double shell_split_mips = 0;
  // Coarsening along feature chains (SimplifyOptions::collapse_chains): chain vertices collapse
  // along their coarse feature edge, whose input vertices are snapped onto it in the shell's
  // reference copy; the curved feature edge then follows the input chain through P. Not with
  // distance points (constraints, eps_samples) or a beveled shell (the coarsening then keeps
  // the feature vertices, with a warning). false: every feature vertex stays a coarse vertex.
  bool feature_chains = true;
  // Curved-aware coarsening (SimplifyOptions::curved_order, order >= 2): an input vertex may lie
  // up to curved_linear_factor × ε from the *linear* middle surface when the face's fully curved
  // patch (the step-3 interpolant) is within curved_margin × ε of every point the face owns.
  // The coarsening also asks such faces' slabs (on the shell's base) to certify fully curved,
  // and their neighbours' with the shared edges curved. Full curving can still be refused later
  // (thickening in thin parts); if the final surface then misses ε somewhere, the attempt is
  // discarded and the input vertices of those faces and of the faces within two edge steps of
  // them keep the linear bound in the next one. The first attempt that misses on no fewer faces
  // than the one before widens that set, once, to the faces around every needed face whose slab
  // the thickening pulled above the shell's base in any attempt so far (thin parts, where the
  // misses move). After curved_attempts attempts, or a second such attempt, the linear bound
  // holds everywhere (the behaviour with curved_coarsening = false).
  // curved_repair: an attempt after a miss does not coarsen the input again; it repairs the last
  // attempt's coarse shell locally, splitting the edges of the faces that own an input vertex
  // now kept under the linear bound until every such vertex is within ε of the linear surface
  // (SimplifyOptions::repair), and curves, fills and checks again. Where the splits cannot
  // reach the bound (the invariants refuse them) the attempt coarsens the input as before.
  bool curved_coarsening = true;
  bool curved_repair = true;
  // Two-phase curved-aware coarsening (issue 22): once the first attempt has missed (and the
  // repair of its shell, with curved_repair, failed), the input's shell is coarsened once under
  // the linear bound, and every later attempt is a resumed coarsening of that shell
  // (SimplifyOptions::resume) instead of a coarsening of the input. Measured on six dev meshes,
  // K = 3 (meshing/curved/README.md): identical where the first attempt or its repair succeeds;
  // at ε = 0.5% bunny 1,556 -> 988 faces in 20.3 -> 12.4 s, fertility 1,114 -> 842 in 21.4 ->
  // 10.6 s, rocker_arm 916 -> 868 in 31.8 -> 19.8 s; at most 6% more faces (bunny 1%).
  bool two_phase = true;
  // With two_phase, deterministic and more than one thread: the first attempt's linear phase is
  // started beside it, on a thread of its own, before anyone knows whether it will be needed
  // (the first attempt coarsens on one thread, so the second core is idle). It is cancelled as
  // soon as an attempt's curved surface meets ε; where the repair fails it is waited for instead
  // of being run then. The same computations either way: the mesh is bit-identical.
  bool concurrent_linear_phase = true;
  // ... only for shells of at most this many prisms: the second coarsening raises the peak
  // memory by 50-80% (igea, 268,686 faces: 1,227 -> 2,225 MiB; knot2 220 -> 324 MiB), which on
  // large inputs outweighs a gain that only the runs whose repair fails see.
  int concurrent_linear_phase_max_faces = 100000;
  double curved_linear_factor = 3.0;
  double curved_margin = 0.95;
  int curved_attempts = 4;
  int threads = 0;  // 0: oneTBB default
  // The coarsening is the only stage whose result depends on thread timing (the editing
  // scheduler's try-locks). Deterministic runs coarsen on one thread, so the same input and
  // options give a bit-identical mesh; false coarsens on `threads` workers (about 1.6x faster on
  // two cores, the mesh varies from run to run).
  bool deterministic = true;
  // Vertex smoothing of the slab layer's inner surface and of the interior under certified
  // positivity, boundary frozen (optimize.hpp); 0 sweeps: off.
  OptimizeOptions optimize;
  // Also mesh the region between the curved surface and a box (cell tags 3: outer slab layer, 4:
  // the rest); the curved surface becomes an interface whose nodes are shared by both sides. The
  // box is the input's bounding box padded by exterior_padding × its longest edge, pushed out
  // where the outer slab surface comes closer to it than a quarter of that.
  bool exterior = false;
  double exterior_padding = 0.25;
};

struct CurvedMeshStats {
  int input_vertices = 0, input_faces = 0, feature_edges = 0, frozen_vertices = 0;
  // Given feature edges and connected curves of them dropped as smaller than
  // CurvedMeshOptions::feature_min_size × ε.
  int small_feature_edges = 0, small_feature_curves = 0;
  // Open feature-curve ends cut back by CurvedMeshOptions::feature_end_trim, edges removed.
  int trimmed_feature_ends = 0, trimmed_feature_edges = 0;
  int singular_vertices = 0;
  int beveled_faces = 0;  // input faces refined by topological beveling (0: not needed)
  // Thin-part refinement (CurvedMeshOptions::thin_refine_ratio): input faces refined, bisections,
  // input edges above the ratio and the worst edge / thickness, before and after.
  int thin_refined_faces = 0, thin_splits = 0, thin_edges_before = 0, thin_edges_after = 0;
  int thin_shape_refusals = 0;  // bisections the thin refinement left out for a child's shape
  double thin_max_ratio_before = 0, thin_max_ratio_after = 0;
  // Shape refinement (CurvedMeshOptions::shape_refine): faces that qualified before and after
  // (of those before, spike_faces were left alone at cone tips: ShapeRefineOptions::
  // min_cone_angle), bisections (of which on feature edges), input faces refined.
  int shape_poor_before = 0, shape_poor_after = 0, shape_spike_faces = 0, shape_splits = 0,
      shape_feature_splits = 0, shape_refined_faces = 0;
  bool shape_budget_reached = false;
  // Non-empty: meshing the thin- or shape-refined input failed with this error, and the mesh is
  // that of the unrefined input (the counts above are then 0).
  std::string thin_fallback;
  // Non-empty: the map of the mesh of the refined input missed its round trip (this message,
  // then which refinement was dropped), and the mesh is that of the input refined less.
  std::string roundtrip_fallback;
  int shell_faces = 0, coarse_faces = 0;
  // Coarsening operations that succeeded (simplify.hpp), and the coarse shell's half-thickness
  // (the smaller half-pillar per vertex) relative to the longest bbox edge.
  int coarsen_collapses = 0, coarsen_flips = 0, coarsen_rotations = 0, coarsen_zooms = 0,
      coarsen_pans = 0, coarsen_splits = 0, coarsen_chain_collapses = 0;
  // SimplifyStats::relaxed_pillars and min_section_bound of the coarsening.
  int coarsen_relaxed_pillars = 0;
  double coarsen_min_section_bound = 0;
  // Input feature vertices inside coarse feature edges (snapped in the reference copy), and the
  // largest distance between one and its snapped point, relative to the longest bbox edge.
  int snapped_vertices = 0;
  double chain_max_distance_rel = 0;
  double coarse_median_thickness_rel = 0, coarse_min_thickness_rel = 0;
  std::vector<std::pair<std::string, double>> coarsen_seconds;  // per operation kind
  // Collapses refused, by reason (shell::SimplifyStats::Rejections): why coarsening stopped.
  std::vector<std::pair<std::string, long>> coarsen_rejections;
  bool shell_section_verified = false;
  int shell_non_section_prisms = 0;
  // verify_shell's distortion: the smallest half-pillar/normal cosine over section-contact pairs.
  double shell_min_pillar_cos = 1;
  // verify_shell's faces of the feature chains' reference copy flattened below
  // k_min_reference_area_ratio of their input area (the map's round-trip checks see the harm).
  int shell_reference_collapsed_faces = 0;
  int faces_fully_curved = 0, faces_blended = 0, faces_linear = 0;
  // Faces whose fully curved patch (first curving round) was refused: slab tets not certified
  // positive, or an input vertex farther than eps from the patch (why faces end blended).
  int curve_refused_certificate = 0, curve_refused_distance = 0;
  // Exterior: linear faces whose outer slab (the shell's top) was not certified, left to the
  // outer surface's thickening, which certifies every face or fails.
  int curve_deferred_outer = 0;
  // Linear faces whose slab tets the floating-point certificate left undecided (none certified
  // non-positive; the shell's exact test says positive), left to the thickening likewise.
  int curve_deferred_undecided = 0;
  // Faces whose α rose again once the slab layer was deepened (the counts above are final).
  int faces_recurved = 0;
  // Faces whose α the quality floor lowered after the recurving (curve_quality_floor).
  int faces_lowered_for_quality = 0;
  // curve_distortion_floor: faces below it (of which folded) before and after, of the last
  // thickening, and faces whose α it lowered.
  int distorted_faces_before = 0, distorted_faces_after = 0;
  int folded_faces_before = 0, folded_faces_after = 0;
  int distorted_needed_after = 0;  // of distorted_faces_after: faces that need full curving
  int faces_lowered_for_distortion = 0;
  // Construction-time embedding of the curved boundary (Builder::embed_boundary): pairs of coarse
  // faces whose curved patches, sampled 2K per edge, intersect after the recurving, before and
  // after the repair at the last thickening; repair rounds and faces whose α the repair lowered,
  // over every thickening (a failed interior fill thickens again).
  int embedding_pairs_before = 0, embedding_pairs_after = 0, embedding_rounds = 0;
  int faces_lowered_for_embedding = 0;
  // Faces whose slab keeps the full shear t · d (slab_nodes.hpp): the low-degree slab nodes were
  // not certified there (thin slabs under an inward bulge). 0 at K ≤ 2.
  int faces_sheared = 0;
  int distance_points = 0;  // constraint points + samples (besides the input vertices)
  int fiber_misses = 0;     // curved nodes whose fiber found no input point (kept linear)
  int curving_rounds = 0;
  int slab_tets = 0, interior_tets = 0, nodes = 0;
  int outer_slab_tets = 0, exterior_tets = 0;  // --exterior
  Eigen::Vector3d exterior_box_lo = Eigen::Vector3d::Zero(),
                  exterior_box_hi = Eigen::Vector3d::Zero();  // --exterior: the outer box
  int thickened_vertices = 0;
  // Exterior: outer surface vertices raised beyond the shell's top, and pulled below it (toward
  // the middle surface) to clear self-intersections of the shell's top.
  int outer_raised_vertices = 0, outer_lowered_vertices = 0;
  double linear_max_distance_rel = 0;
  // Curved-aware coarsening: in effect for the kept attempt, its number (1 = first), and the
  // input vertices kept under the linear bound after the discarded ones; curved_widened: that
  // set was widened to the slabs pulled above the shell's base.
  bool curved_coarsening = false, curved_widened = false;
  int curved_attempts = 0, strict_vertices = 0;
  // curved_repair: attempts that repaired the previous coarse shell (curved_repairs), the
  // splits they made in all (repair_splits), and repairs that could not reach the bound and
  // coarsened the input again instead (repair_failures).
  int curved_repairs = 0, repair_splits = 0, repair_failures = 0;
  // ε levels (build_curved_mesh_levels): the coarse faces of the finer level this level's
  // coarsening resumed from (0: coarsened from the input's shell).
  int coarsen_start_faces = 0;
  // Two-phase coarsening (CurvedMeshOptions::two_phase): the faces of the linear-bound shell the
  // attempts after the first resumed from (0: not run, the first attempt or its repair held).
  int linear_phase_faces = 0;
  // Its own run time, and whether it ran beside the first attempt (concurrent_linear_phase; the
  // stage "coarsen (linear phase)" is then only the wait for it).
  double linear_phase_seconds = 0;
  bool linear_phase_concurrent = false;
  OptimizeStats optimize;
  std::vector<std::pair<std::string, double>> stage_seconds;
};

struct CurvedMesh {
  LagrangeMesh mesh;  // order-k tets; cell_tags 1: slab, 2: interior, 3: outer slab, 4: exterior
  BoundaryMap map;    // φ for every input vertex
  // The coarse shell the boundary was curved in: boundary triangle f of `map` is shell face f
  // (rotated to its smallest vertex id), so φ⁻¹(f, u, v) is the shell projection P_T(f, u, v).
  meshing::shell::Shell shell;
};

// Throws InputError for an input the shell rejects, MeshingError naming the stage when a stage
// cannot meet its guarantees (e.g. interior boundary recovery).
CurvedMesh build_curved_mesh(const SurfaceMesh& input, const CurvedMeshOptions& options,
                             CurvedMeshStats& stats, const ProgressFn& progress = {});

// ε levels from one coarsening (issue 22): one mesh per level, each with options' other settings
// and the level's bound (eps_rel, eps_scale as in CurvedMeshOptions). The shell is built once;
// the finest level coarsens it, and every coarser level resumes from the coarse shell the finer
// one kept (the larger bounds hold there already), so an extra level costs a short coarsening
// plus its own curving, fill and stitch. stats[i] belongs to levels[i]: its stage_seconds hold
// that level's stages only ("shell" in the finest one), coarsen_start_faces where it resumed
// from. The meshes are those build_curved_mesh gives at the finest level and may differ from
// its results at the others (a different start for the collapses).
struct EpsLevel {
  double eps_rel = 1e-2;
  std::vector<double> eps_scale;  // empty or one factor in (0, 1] per input vertex
};
std::vector<CurvedMesh> build_curved_mesh_levels(const SurfaceMesh& input,
                                                 const CurvedMeshOptions& options,
                                                 const std::vector<EpsLevel>& levels,
                                                 std::vector<CurvedMeshStats>& stats,
                                                 const ProgressFn& progress = {});

}  // namespace curvefem::meshing::curved
