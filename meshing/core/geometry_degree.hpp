#pragma once
// A tet mesh whose cells' maps are lowered to degree m: the same order k, cells and node ids,
// each cell's map replaced by its degree-m Lagrange interpolant (the map read at the order-m
// lattice points of the cell, evaluated at its order-k nodes). Corner nodes and the points of the
// order-m lattice keep their positions, so the DOFs of a degree-p space (p ≤ m) sit where they
// sat; shared entities get one position (an interpolant on a face depends on that face only).
//
// Why (issue 20): a degree-p space on a map of degree k > p does not contain the linear
// functions — for elasticity the rigid rotations —, and on curved slab tets whose map carries
// much cubic content (thin parts, coarse inputs) P2 elasticity locked (the elephant at k = 3, p =
// 2: half the reference displacement). `curvefem run` therefore solves on the degree-p
// interpolant of an order-k mesh (discretization.geometry "iso", the default) after certifying
// it, and on the mesh itself only when asked ("mesh").

#include <functional>
#include <vector>

#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem {

/// Accepts cell c with these nodes (#nodes per cell × 3, canonical order)?
using CellAccept = std::function<bool(int cell, const Eigen::MatrixXd& nodes)>;

/// m in 1..order. With `accept` (e.g. a positivity certificate), cells it refuses keep their own
/// map — with every node they hold — and their neighbours are asked again, until every cell is
/// accepted or keeps its map; `kept` receives how many kept it (a cell kept at its own map is
/// accepted by the caller's earlier validation). InputError for a non-tet mesh or m outside
/// 1..order.
LagrangeMesh lower_geometry_degree(const LagrangeMesh& mesh, int m, const CellAccept& accept = {},
                                   int* kept = nullptr);

}  // namespace curvefem
