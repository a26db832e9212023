#pragma once
// Shell simplification on meshing/editing (thesis §4.3.2; reference-notes §3.6): rounds of
//   collapse  shortest-first half-edge collapses of the middle surface that keep the kept
//             vertex's pillar,
//   split     (split_mips > 0) the longest edge of a badly shaped middle triangle, at an input
//             vertex near its midpoint,
//   flip      edge swaps of the middle surface that lower the worst 2-D MIPS of the two faces,
//   rotate    pillar re-orientation: a vertex's pillar turns to the most visible direction
//             (extrusion_direction.hpp, floating-point active set only: a star it cannot
//             decide is skipped) of its coarse star faces and the input faces its prisms track,
//             keeping both half-lengths, so the pillars follow the coarse surface,
//   zoom      thickness growth: a vertex's base and top move away from the middle surface along
//             the pillar (doubling each half, capped by max_half_thickness and by a fraction of
//             the ray distance to the input), so a coarser middle surface still has the input
//             inside its prisms; pillars pinned thin (zoom_pinned) get up to zoom_passes
//             doublings a round.
// The middle surface keeps the input's vertices (no tangential moves). Every operation is
// accepted only if every new or changed prism
//   I1  passes the exact 24-tet positivity test,
//   I2  keeps the input a section: every input triangle in section contact with its canonical
//       split tets has a normal with cos(angle) >= section_cos to each non-singular half-pillar
//       (and a positive exact sign),
//   I3  has base and top triangles that do not intersect the input (exact; pinch contact only),
// and the input faces covered by the removed prisms stay covered by the new ones. Singular
// vertices never move or disappear. Runs through the parallel scheduler.

#include <array>
#include <atomic>
#include <functional>
#include <stdexcept>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/editing/scheduler.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::meshing::shell {

struct SimplifyOptions {
  int threads = 1;
  // With threads == 1: the pillar rotations and thickness growths run on this many threads as
  // ordered levels (editing::ExecutePass::level_region), giving the one-thread shell exactly.
  int smoothing_threads = 1;
  bool smoothing_levels_reversed = false;  // tests: editing::ExecutePass::reverse_levels
  // One-thread collapse passes replay a refusal while nothing it read has changed (same answers,
  // meshing/shell/README.md "What the checks skip"); false runs every check (for comparisons).
  bool replay_refusals = true;
  // Projection distortion bound (thesis §4.4, "optional invariant"): every input face in section
  // contact with a new prism makes cos(angle) >= section_cos with each of its non-singular
  // half-pillars. 0 is the bare section condition (a positive exact sign), under which a pillar
  // may end up tangent to an input face up to rounding: a torus shell coarsened that way passed
  // every exact check, yet floating-point P sent 3 vertices 0.0093 away (meshing/shell/README.md).
  // 0.01 (about 89.4°) is bichon's distortion_bound; BPS uses 1e-3.
  double section_cos = k_section_cos;
  // A pillar of the starting shell that already leans further than that from an input face in
  // section contact with its prisms (a knife edge's pillar: no direction crosses knife_disc's
  // 0.5° wedge at 0.01 with both sides, its rim pillars make 0.0074) has this fraction of its
  // smallest such cosine as its bound instead, kept through the operations (a split's new
  // pillar takes the smaller of its ends'). The absolute bound refused every operation that let
  // such a pillar cover one more face (knife_disc: 416 -> 526 coarse prisms), yet the fraction
  // keeps each cosine as far from rounding as the input allows. 0: the absolute bound.
  double section_cos_relative = k_section_cos_relative;
  // A chain collapse may not flatten a face of the reference copy below this fraction of its
  // input face's area (InputSurfaceIndex::face_area_ratio; k_min_reference_area_ratio). 0: only
  // exactly degenerate faces are refused.
  double min_reference_area_ratio = k_min_reference_area_ratio;
  int rounds = 3;  // collapse passes (a pass re-seeds every edge)
  // > 0: distance bound. Every input vertex is owned by the prism that contains it; a collapse is
  // accepted only if each owned vertex x lies in one of the new prisms, at prism coordinates
  // (u, v, h), with |x - mid(u, v)| <= max_distance (mid: the linear middle triangle).
  double max_distance = 0;
  // Further points on the input where the distance bound holds too (constraint points, dense
  // samples between the input vertices), each with the face of the given shell whose prism holds
  // it (within the bound of that face's middle triangle). Owned and re-homed like input vertices.
  std::vector<Eigen::Vector3d> extra_points;
  std::vector<int> extra_point_faces;
  // Spatially varying bound (issue 22): empty, or one factor in (0, 1] per distance point (the
  // input vertices, then the extra points). Point x's bounds are max_distance ·
  // distance_scale[x] (and likewise the curved-aware relaxed_distance and curved_distance);
  // SimplifyStats::max_distance is then the largest distance / distance_scale.
  std::vector<double> distance_scale;
  // #input vertices or empty: input vertices whose middle vertex must never be collapsed away
  // (feature vertices, user constraints).
  std::vector<char> frozen_input_vertices;
  // > 0: shape guard on the middle triangles. A collapse whose new triangles have a worse maximum
  // 2-D MIPS energy (|e0|²+|e1|²+|e2|²)/(2√3·area), 2 for the equilateral triangle, than both
  // the removed ones and this bound is rejected.
  double max_mips = 0;
  // Relative slack of that guard where the removed triangles are already worse than max_mips:
  // a collapse may then raise the worst MIPS of its star by this factor. In bands of needle
  // triangles (CAD tessellations) most collapses leave a needle a fraction of a percent worse
  // than the one they remove, and the strict guard refused them all (abc_00000008: 400 refusals
  // of needles of MIPS 50-1,650 by less than 2%; 48 of 406 coarse faces kept a MIPS above 100).
  double shape_slack = 0;
  // > 0: thickness guard (issue 21). The local thickness T(x) of the object at each input vertex
  // x is the distance along the inward vertex normal to the input beyond x's own faces. A
  // collapse whose new middle triangles have an edge (a, b) longer than this many times
  // min(T(a), T(b)), and longer in that ratio than every removed triangle's, is rejected: in a
  // thin part the slab tets, no deeper than the part is thick, stay this flat at worst.
  double max_edge_per_thickness = 0;
  bool flips = true;   // flip passes between collapse rounds
  bool rotate = true;  // pillar rotation passes
  // Pan passes (one thread): a middle vertex next to a collapse refused for the triangle shape
  // moves to a neighbouring input vertex where its star is better shaped. Needs max_mips (pans
  // follow shape refusals). The curved mesher turns them on (CurvedMeshOptions::shell_pan).
  bool pan = false;
  // > 0 (needs max_distance, whose owned input vertices it picks from): split passes after each
  // collapse pass. The longest edge of every middle triangle with a 2-D MIPS above this gets a
  // new middle vertex on the input vertex of its two prisms nearest to its midpoint, kept when
  // the worst MIPS of the new triangles is strictly lower and the invariants hold.
  double split_mips = 0;
  // Coarsening along feature chains (thesis §5.3; needs max_distance, no extra_points): input
  // feature edges as vertex pairs. A middle vertex on an input vertex with exactly two of them
  // (a chain vertex; it must be frozen for the other operations) may collapse into a neighbour
  // along a coarse feature edge. The input vertices inside each coarse feature edge are snapped,
  // in a reference copy of the input, onto that straight edge by arc length
  // (Shell::reference); the invariants are checked on that copy with exact predicates, and the
  // distance bound holds between each such vertex and its snapped point. Chain collapses run
  // on one thread after each collapse pass.
  std::vector<std::array<int, 2>> feature_edges;
  bool collapse_chains = false;
  // A chain collapse re-checks the prisms near the faces it snaps: those it did not change only
  // against the snapped faces (their verdicts on the others stand). true: every such prism in
  // full, as before; the same result, slower (kept to test that).
  bool chain_full_recheck = false;
  // A chain collapse finds the live prisms near the faces it snaps through a uniform grid over
  // the prisms' boxes; false tests every live prism's box (the same prisms; kept to test that).
  bool chain_grid = true;
  // >= 2 (needs max_distance): the curved-aware bound. An input vertex not marked in
  // strict_input_vertices may lie up to relaxed_distance (>= max_distance) from the linear middle
  // triangle, provided every new prism owning such a vertex passes within curved_distance
  // (0: max_distance) of every point it owns with its curved middle triangle of this order: the
  // Lagrange triangle through the middle corners and, at the other lattice nodes, the input
  // points on the nodes' fibers (the curved mesher's patch at full curving). Extra points and
  // the chains' snapped vertices keep max_distance.
  int curved_order = 0;
  double relaxed_distance = 0, curved_distance = 0;
  // > 0: a needed face's fully curved patch must also have its area element |x_u × x_v| (order-4k
  // lattice) nowhere below this fraction of its largest, nor turned against its corners' plane:
  // the curved mesher can lower the curving of a distorted face only when it does not need it.
  double curved_min_area_ratio = 0;
  std::vector<char> strict_input_vertices;  // #input vertices or empty (none strict)
  // Optional, with curved_order: is the bottom half-prism of such a face, with corners base and
  // mid (rotated to the smallest id; canonical split of type_a) and its middle triangle displaced
  // by d (node − linear point per triangle lattice node, canonical order), a valid curved slab?
  // `top` (the same corners' tops) is for callers that also use the top half-prism (an exterior).
  // The curved mesher certifies its slab tets (the coarsening cannot see curved elements).
  std::function<bool(const std::array<Eigen::Vector3d, 3>& base,
                     const std::array<Eigen::Vector3d, 3>& mid,
                     const std::array<Eigen::Vector3d, 3>& top, bool type_a,
                     const std::vector<Eigen::Vector3d>& d)>
      curved_slab_ok;
  double zoom = 0;  // > 0: thickness growth passes, each half-pillar capped at this length
  // Zoom passes per round (each doubles a half-pillar at most; a pass's successes flag their
  // stars for the next). With 1, a shell pinned thin by a sliver grows by 2 a round only, too
  // slowly for the coarsening to remove the sliver once it could (tr12j_occt, K = 4: a
  // 0.016-wide input strip kept as a 179.9° coarse cap, half-pillars 9e-4 at its ends).
  // CurvedMeshOptions::shell_zoom_passes has the measurements (mixed, hence 1 by default).
  int zoom_passes = 1;
  // The passes after the first grow only pillars whose longer half is shorter than this × the
  // mean length of their star's edges (pinned thin; 0: none).
  double zoom_pinned = 0.05;
  double zoom_ray_fraction = 0.45;  // ... and at this fraction of the ray distance to the input
  // Repair mode (needs max_distance; the curved mesher's local repair of faces that missed ε
  // once curved): `shell` is the output of an earlier simplify_shell with the same input and extra
  // points, `owned_points` what that run returned in SimplifyStats::owned_points, and points
  // may now lie farther than max_distance from their linear middle triangle where their bound is
  // max_distance (*violating* points): strict_input_vertices the earlier run let beyond it, or,
  // without curved_order, any point under a max_distance smaller than the earlier run's (a
  // coarse-to-fine refinement of the same coarse shell). No collapses or smoothing: up to
  // repair_passes passes, each splitting the longest edge of every face owning a violating point
  // (then the second longest and the shortest where that was refused) followed by a flip pass
  // (with `flips`). The new vertex goes on an unoccupied input vertex the two prisms own: the
  // nearest to the edge's midpoint within a third of the edge first, then the violating points
  // themselves; never a vertex snapped onto a feature chain, and never on an edge in
  // feature_edges or a coarse feature edge of the shell's chains. Pillar directions tried: the
  // ends' mean, the input's vertex normal, the new middle triangles' mean normal, with halves
  // of 1 … 1/8 of the ends' shorter ones. A split is kept when I1–I3 and the coverage hold for
  // the new prisms, the shape and thickness guards hold, every owned point stays within its
  // bound or, if violating, no farther than the farthest violating point of the two old prisms
  // was, and the curved-aware checks hold on the non-violating points.
  // SimplifyStats::violating_points says how many are left (0: repaired).
  bool repair = false;
  std::vector<std::vector<int>> owned_points;
  int repair_passes = 16;
  // Resume mode (issue 22, ε levels from one coarsening): `shell` and `owned_points` as in repair
  // mode, typically the coarse shell of a smaller bound, coarsened further under this one. Points
  // beyond their bound here (only when the bounds are not larger than the earlier run's) are
  // first repaired as in repair mode; if some are left (SimplifyStats::violating_points > 0) the
  // shell is returned without collapses, else the collapse rounds run as from the input's shell.
  // Feature chains resume too: the coarse feature edges are rebuilt from the shell's reference
  // copy (each snapped vertex inside the coarse edge between its two ends).
  bool resume = false;
  // Optional: a run started speculatively (the curved mesher's concurrent linear phase) is
  // stopped once *cancel becomes true: the next operation's check throws SimplifyCancelled, and
  // the partly simplified shell is dropped.
  const std::atomic<bool>* cancel = nullptr;
};

/// Thrown by simplify_shell when SimplifyOptions::cancel became true.
struct SimplifyCancelled : std::runtime_error {
  SimplifyCancelled() : std::runtime_error("simplify: cancelled") {}
};

struct SimplifyStats {
  int faces_before = 0, faces_after = 0;
  std::vector<std::pair<std::string, editing::PassStats>> passes;  // "collapse", "flip", ...
  int collapses = 0, flips = 0, rotations = 0, zooms = 0, pans = 0, splits = 0;
  int chain_collapses = 0;
  int snapped_vertices = 0;       // input vertices inside coarse feature edges at the end
  double chain_max_distance = 0;  // max |x - snapped x| over them
  // Collapses refused, by the first check that failed: the triangle shape bound, the distance
  // bound, then per new prism I1 positivity, I3 intersection, I2 section, and coverage (a prism
  // touching no input face, or an input face the old prisms touched left uncovered). Collapses
  // refused earlier (link condition, frozen or singular vertex) are not counted here.
  struct Rejections {
    long shape = 0, distance = 0, positivity = 0, intersection = 0, section = 0, coverage = 0;
    long curved = 0;     // the curved-aware bound (curved_order)
    long thickness = 0;  // the thickness guard (max_edge_per_thickness)
  } collapse_rejections;
  // The smaller half-pillar per live non-singular vertex at the end (absolute lengths).
  double min_half_thickness = 0, median_half_thickness = 0, max_half_thickness = 0;
  double max_distance =
      0;  // max |x - mid(u, v)| / distance_scale(x) over owned points (if bounded)
  // With max_distance: per output face, the points its prism owns (input vertex x, or extra
  // point x - #input V), the input of a later repair (SimplifyOptions::owned_points).
  std::vector<std::vector<int>> owned_points;
  int violating_points = 0;    // repair mode: strict points still beyond max_distance at the end
  int repair_passes = 0;       // repair mode: split passes run
  long replayed_refusals = 0;  // collapse refusals replayed (SimplifyOptions::replay_refusals)
  // Chain collapses: live prisms whose boxes were tested against the snapped faces, and the
  // live prisms there were (SimplifyOptions::chain_grid), summed over the attempts.
  long long chain_prisms_tested = 0, chain_prisms_live = 0;
  // Pillars whose distortion bound is SimplifyOptions::section_cos_relative × the starting
  // shell's cosine (below section_cos), and the smallest such bound (section_cos if none).
  int relaxed_pillars = 0;
  double min_section_bound = 0;
  double seconds = 0;
};

Shell simplify_shell(const Shell& shell, const SurfaceMesh& input, const SimplifyOptions& options,
                     SimplifyStats& stats);

}  // namespace curvefem::meshing::shell
