// Reading and writing triangle surfaces: OBJ, OFF, STL (ascii/binary), PLY (ascii/binary),
// Gmsh MSH 2.2 and 4.1.
//
// Readers never crash and never read out of bounds: any defect (empty or truncated file, polygon
// with more than 3 vertices, NaN/inf coordinate, index out of range or negative, bad header, count
// mismatch) throws InputError naming the file, the line (text) or byte offset (binary) and the
// defect. Face tags: OBJ `g`/`usemtl` groups (numbered 1.. in order of first appearance, names in
// tag_names), PLY integer face property (any name among tag/tags/label/region/group/
// physical/material_index, else the first extra int face property), MSH physical tags. STL vertices
// are welded when bit-identical. OBJ indices may be negative (relative) as the format allows.
// Writers are atomic (temp file + rename).
//
// Details: a file that cannot be opened throws IoError. A file without any triangle is an
// InputError (a reader never returns an empty surface). OBJ faces before the first group get tag 0
// and `g` groups win over `usemtl` when both occur. MSH: faces come in element-id order, only nodes
// used by triangles are kept (in file order), tag names come from dimension-2 $PhysicalNames.
// Writers use the shortest decimal text that reads back to the same double, so OBJ/OFF/PLY/MSH
// round trips are exact; OBJ writes tags as `g` groups (`tag_<t>` when unnamed) and therefore
// renumbers them by first appearance on reading; binary STL stores floats; PLY writes
// "comment tag_name <t> <name>" lines that the reader turns back into tag_names.
#pragma once

#include <filesystem>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::io {

enum class SurfaceFormat { obj, off, stl_ascii, stl_binary, ply_ascii, ply_binary, msh22, msh41 };

/// Chooses the reader from the extension (.obj .off .stl .ply .msh, case-insensitive); STL ascii
/// vs binary and MSH version are recognised from the content.
SurfaceMesh read_surface(const std::filesystem::path& path);

SurfaceMesh read_obj(const std::filesystem::path& path);
SurfaceMesh read_off(const std::filesystem::path& path);
SurfaceMesh read_stl(const std::filesystem::path& path);
SurfaceMesh read_ply(const std::filesystem::path& path);
/// Triangles of a MSH 2.2 or 4.1 file (ascii or binary); all other element types are ignored.
SurfaceMesh read_msh_surface(const std::filesystem::path& path);

/// Writes the surface (with tags where the format can hold them) atomically.
void write_surface(const std::filesystem::path& path, const SurfaceMesh& mesh,
                   SurfaceFormat format);
/// Format from the extension (.obj .off .stl → binary .ply → binary .msh → 4.1).
SurfaceFormat surface_format_from_extension(const std::filesystem::path& path);

}  // namespace curvefem::io
