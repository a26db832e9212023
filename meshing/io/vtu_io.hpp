// VTK XML unstructured grids (.vtu) of Lagrange simplices of order 1..4 with point and cell data.
//
// Cells: order 1 → VTK_TETRA (10) / VTK_TRIANGLE (5); order ≥ 2 → VTK_LAGRANGE_TETRAHEDRON (71) /
// VTK_LAGRANGE_TRIANGLE (69). Nodes are shared between cells exactly as in the LagrangeMesh (point
// i = mesh.nodes row i), so ParaView sees one connected mesh. Written with VTK's own XML writer:
// binary appended data, zlib-compressed, UInt64 headers, Int64 connectivity; atomically (no file
// is left behind on failure).
//
// Node order: the VTK ↔ canonical permutation (lagrange_nodes.hpp) is built at run time by
// matching VTK's own reference coordinates (vtkCell::GetParametricCoords), never by hand, and
// cached. For tetrahedra of order ≥ 2 and triangles of order ≥ 2 it is not the identity.
//
// Data: MeshFields point_data (#nodes tuples) and cell_data (#cells tuples) become Float64 arrays
// with `components` components; cell_tags (if non-empty) become the Int32 cell array "tag", which
// read_vtu turns back into cell_tags ("tag" is therefore reserved as a cell field name).
//
// Reading accepts VTK types 5/10/22/24/69/71 — complete Lagrange triangles or tetrahedra of order
// 1..4, including VTK_QUADRATIC_TRIANGLE 22 / VTK_QUADRATIC_TETRA 24 — of one kind and one order
// per file. Every numeric point/cell array comes back as a Field (converted to double).
//
// Errors: write_vtu throws InputError for an invalid mesh or field sizes (before touching the
// disk) and IoError when VTK cannot write. read_vtu throws InputError naming the file for a
// missing, empty, garbage, truncated or corrupted file (VTK's error messages are captured into the
// exception and kept off stderr), for a file without cells, and naming the cell for an unsupported
// or mixed cell type or an out-of-range point id. Before VTK sees the file, a pre-flight check
// (vtu_binary_check.hpp) bounds every size the file declares by what it contains: VTK 9.1's reader
// trusts them and dies (SIGFPE/SIGSEGV/heap corruption) on single corrupted bytes. The file is
// therefore read into memory once before VTK reads it.
#pragma once

#include <filesystem>
#include <vector>

#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::io {

void write_vtu(const std::filesystem::path& path, const LagrangeMesh& mesh,
               const MeshFields& fields = {});

struct VtuContent {
  LagrangeMesh mesh;  ///< canonical node order; cell_tags from the "tag" cell array, if any
  MeshFields fields;  ///< all other numeric point and cell arrays, in file order
};
VtuContent read_vtu(const std::filesystem::path& path);

/// perm such that VTK local node i is canonical local node perm[i] (for the cell type write_vtu
/// uses for this kind and order). Writing: vtk_ids[i] = cells(c, perm[i]); reading:
/// cells(c, perm[i]) = vtk_ids[i]. Throws InputError for an order outside 1..4.
std::vector<int> vtk_node_permutation(CellKind kind, int order);

}  // namespace curvefem::io
