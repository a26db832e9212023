#pragma once
// Nodes of the curved slab tets (thesis §5.3, stitching; meshing/curved/README.md step 7): the
// half-prism between a coarse face's curved middle triangle and its linear base (or top) is
// split into 3 tets of order k whose nodes carry the curved displacement of the middle
// triangle into the slab.
//
// Conventions: the middle triangle is a face rotated to its smallest shell id, local vertices
// 0, 1, 2 at reference points (0, 0), (1, 0), (0, 1). Its curved patch is the order-k
// displacement d from the linear triangle, one vector per triangle lattice node in the
// canonical order of meshing/core/lagrange_nodes.hpp, 0 at the three corners.
//
// The slab is the linear prism sheared along its fibers by t · d(u, v) (t the share of the
// middle corners, (u, v) the fiber's triangle point) — but only as far as the patch needs it:
// d = d₂ + r, d₂ the quadratic with d's values at the edge midpoints and r the rest. The
// quadratic part enters as the quadratic interpolant of t · d₂ on each tet (exactly the order-2
// slab), only r as t · r at the order-k nodes. Shearing by the whole t · d (before issue 20) made
// the slab map as cubic as it is quadratic (t · d₂ is cubic) on every curved face at k ≥ 3:
// certified positive, yet a degree-p space on it approximated worse than on the order-2 slab of
// the same mesh — at p = 2 (a cubic map leaves the linear functions out of the space) and at
// p = 3. Every term is a function of the shared sub-simplex only (edge data on the prism's
// sides, 0 on the base), so neighbouring slab tets and the straight interior stay conforming;
// the middle face is the patch itself, and at k = 2 the nodes are those of t · d.
//
// The full shear t · d is kept as a fallback: it stretches every fiber of the column uniformly,
// so it stays positive under a larger inward bulge of a thin slab (measured, k = 3, a slab of
// depth T: certified up to a central bulge of about 0.7 T against 0.45 T). A face whose slab
// certifies only with it uses it (SlabBlend::face = false); a prism side quad, shared with the
// neighbour across its edge, uses the low-degree nodes only when both faces do, so either choice
// conforms (both constructions agree on the middle face, the base and the pillars).

#include <Eigen/Core>
#include <vector>

namespace curvefem::meshing::curved {

/// The patch displacement d (order k, canonical triangle lattice) at (u, v).
Eigen::Vector3d patch_displacement(const std::vector<Eigen::Vector3d>& d, int order, double u,
                                   double v);

/// Where the low-degree construction is used (true) or the full shear t · d (false): inside the
/// prism, and on the side quad over the edge opposite each local vertex.
struct SlabBlend {
  bool face = true;
  bool edge[3] = {true, true, true};
};

/// The nodes (#tet lattice × 3, canonical order) of an order-k slab tet with corners P, corner j
/// above local triangle vertex lv[j] and on the middle triangle when on_mid[j] != 0. Tets with
/// no middle corner come out straight with the low-degree construction. Bit j of `pinched`:
/// corner j stands on a pinched vertex (singular: base = middle, a pillar of length 0); its
/// share of the middle is then that of the other corners of the node's sub-simplex, so an edge
/// from it to a base corner is straight (it is an edge of the inner surface, which the straight
/// interior shares) and one to a middle corner follows the patch, whichever level the tet names
/// the pinched corner by (issue 21: the two namings have one global id, and a slab tet's curved
/// diagonal reached the interior as its edge, which then inverted).
Eigen::MatrixXd slab_tet_nodes(int order, const Eigen::Vector3d (&P)[4], const int (&lv)[4],
                               const int (&on_mid)[4], const std::vector<Eigen::Vector3d>& d,
                               const SlabBlend& blend = {}, unsigned pinched = 0);

}  // namespace curvefem::meshing::curved
