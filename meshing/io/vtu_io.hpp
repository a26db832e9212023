// VTK XML unstructured grids (.vtu) of Lagrange simplices of order 1..4 with point and cell data.
//
// Cells: order 1 → VTK_TETRA (10) / VTK_TRIANGLE (5); order ≥ 2 → VTK_LAGRANGE_TETRAHEDRON (71) /
// VTK_LAGRANGE_TRIANGLE (69). Written with VTK's own XML writer: binary, appended, zlib-compressed,
// UInt64 headers; atomically. The VTK ↔ canonical node permutation (lagrange_nodes.hpp) is built
// at run time by matching reference coordinates with VTK's own cells, never by hand.
// Reading accepts those cell types (and VTK_QUADRATIC_TETRA 24 / VTK_QUADRATIC_TRIANGLE 22), of one
// kind and order per file; anything else is an InputError naming the cell.
#pragma once

#include <filesystem>
#include <vector>

#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::io {

void write_vtu(const std::filesystem::path& path, const LagrangeMesh& mesh,
               const MeshFields& fields = {});

struct VtuContent {
  LagrangeMesh mesh;
  MeshFields fields;
};
VtuContent read_vtu(const std::filesystem::path& path);

/// perm such that VTK local node i is canonical local node perm[i].
std::vector<int> vtk_node_permutation(CellKind kind, int order);

}  // namespace curvefem::io
