// Internal: node permutations between a file format's local node order and curvefem's canonical
// order (meshing/core/lagrange_nodes.hpp), found by matching reference coordinates.
//
// Both formats (VTK, Gmsh) and curvefem use the same reference simplex v0 = 0, v1 = e_x, v2 = e_y
// (, v3 = e_z), so a node of the foreign order and its canonical counterpart have the same
// reference coordinates. Matching (not hand-written tables) covers every order and cannot drift
// out of sync with the libraries.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "meshing/core/lagrange_nodes.hpp"

namespace curvefem::io::detail {

/// foreign: #n × ≥dim reference coordinates, row i = foreign local node i (extra columns, e.g. the
/// z of a triangle, must be ~0). Returns perm (size n) with foreign node i = canonical node
/// perm[i]. Each foreign node is matched to its nearest canonical node; the match must be
/// closer than `tolerance` and one-to-one, else curvefem::Error naming `source` (a library
/// disagreeing with the reference simplex is a bug, not bad input).
std::vector<int> match_reference_nodes(const Eigen::MatrixXd& foreign, CellKind kind, int order,
                                       double tolerance, const std::string& source);

/// Largest |foreign - canonical[perm]| over the nodes: how far the library's stored coordinates
/// are from the exact lattice (VTK rounds some to ~1e-6). For tests and logs.
double reference_node_mismatch(const Eigen::MatrixXd& foreign, CellKind kind, int order,
                               const std::vector<int>& perm);

}  // namespace curvefem::io::detail
