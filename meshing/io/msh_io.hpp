// Gmsh MSH 4.1 output and input of Lagrange simplex meshes of order 1..4.
//
// Element types: tetrahedra 4/11/29/30, triangles 2/9/21/23 (order 1/2/3/4, complete Lagrange
// elements; the 15-node triangle is type 23 — 22 is Gmsh's incomplete 12-node one). Type numbers
// come from gmsh::model::mesh::getElementType, never hard-coded. The Gmsh ↔ canonical node permutation is
// built by matching reference coordinates from gmsh::model::mesh::getElementProperties.
// cell_tags become physical groups. Writing is atomic.
#pragma once

#include <filesystem>
#include <vector>

#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::io {

void write_msh(const std::filesystem::path& path, const LagrangeMesh& mesh);

/// Reads the highest-dimensional simplices (tets if any, else triangles) of a MSH 2.2/4.1 file.
LagrangeMesh read_msh(const std::filesystem::path& path);

/// perm such that Gmsh local node i is canonical local node perm[i].
std::vector<int> gmsh_node_permutation(CellKind kind, int order);

}  // namespace curvefem::io
