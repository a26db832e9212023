// Gmsh MSH 4.1 output and MSH 2.2/4.1 input of Lagrange simplex meshes of order 1..4.
//
// Element types: tetrahedra 4/11/29/30, triangles 2/9/21/23 (order 1/2/3/4, complete Lagrange
// elements; the 15-node triangle is type 23 — 22 is Gmsh's incomplete 12-node one). Type numbers
// come from gmsh::model::mesh::getElementType, never hard-coded. The Gmsh ↔ canonical node
// permutation is built by matching reference coordinates from
// gmsh::model::mesh::getElementProperties. Both are queried once per process and cached; the
// queries do not open a GmshSession and do not touch the current Gmsh model, so they are safe to
// call while holding a session (they initialize Gmsh if nobody has yet).
//
// write_msh writes ascii MSH 4.1 text itself (shortest round-trip number formatting, so
// read_msh(write_msh(m)) reproduces the coordinates bit for bit), atomically:
//   * all nodes (also unreferenced and interior high-order ones), node tag = row + 1;
//   * element tag = cell index + 1 (read_msh restores the cell order from it);
//   * one elementary entity per distinct cell tag; tag t > 0 becomes physical group t (named
//     "tag_t"), tag 0 an entity without physical group. Empty cell_tags: one entity, no physical
//     groups. Negative tags are an InputError (MSH physical tags are positive).
//
// read_msh (built on the internal msh_parser, not on the Gmsh API) takes the highest-dimensional
// complete Lagrange simplices of the file: tetrahedra if there are any, else triangles; other
// elements are ignored (a warning counts ignored elements of that dimension or higher, e.g. hexes).
// Elements are sorted by element tag; nodes are renumbered compactly (referenced nodes only, in
// file order); node order is mapped to canonical; physical tags become cell_tags (0 for an element
// without physical group; cell_tags empty when no element has one). Errors: InputError naming the
// file for a missing/garbage/truncated file (from the parser), no triangles/tetrahedra, mixed
// orders (naming the element tag) or undefined node ids.
#pragma once

#include <filesystem>
#include <vector>

#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::io {

void write_msh(const std::filesystem::path& path, const LagrangeMesh& mesh);

/// Reads the highest-dimensional simplices (tets if any, else triangles) of a MSH 2.2/4.1 file.
LagrangeMesh read_msh(const std::filesystem::path& path);

/// Corner triangles of every triangle element (orders 1..4) of a MSH 2.2/4.1 file with their
/// physical tags (0 = none): the tagged boundary of a volume mesh, for boundary selections.
/// Vertices are the files' nodes at the triangles' corners. InputError if there is no triangle.
SurfaceMesh read_msh_boundary_triangles(const std::filesystem::path& path);

/// perm such that Gmsh local node i is canonical local node perm[i]. Throws InputError for an
/// order outside 1..4.
std::vector<int> gmsh_node_permutation(CellKind kind, int order);

}  // namespace curvefem::io
