// boundary_map.json: the BoundaryMap φ of a `mesh` output (DESIGN.md §2), self-contained in both
// directions: the curved boundary triangles with their own node copy (and the volume node each
// one is), for every input vertex its boundary triangle and (u, v) in it, the distance points,
// the feature edges, and — for φ⁻¹ — the coarse shell's fibers (meshing/core/shell_fibers.hpp:
// layers, rotated faces, the reference copy's moved vertices, per-prism candidate input faces),
// so mapping/ evaluates φ⁻¹ from the file without the shell code. Doubles are written with
// round-trip precision: a read map and fibers equal the written ones bit for bit.
//
// Format "curvefem-boundary-map" version 2. Version 1 stored the shell itself ("shell" block);
// reading it fails with an InputError asking to re-run `curvefem mesh` (the fibers' candidate
// faces come from the shell code, which this module does not link).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "meshing/core/boundary_map.hpp"
#include "meshing/core/shell_fibers.hpp"

namespace curvefem::io {

// 3 (2026-12-04): the fibers may carry the refined surface they cross (ShellFibers::surface_*),
// which a reader of version 2 would ignore and so evaluate φ⁻¹ on the wrong triangles.
inline constexpr int k_boundary_map_version = 3;

/// `input`: the dense input's path, recorded for later runs (absolute, or relative to the file's
/// folder). `fibers` (optional): the coarse shell's fibers the boundary was curved in (φ⁻¹ = P_T
/// on them). `input_checksum` (optional): of the input file's bytes, so that a later run reusing
/// the map (geometry.mesh_dir) can refuse a changed input. Written atomically.
void write_boundary_map(const std::filesystem::path& path, const BoundaryMap& map,
                        const std::string& input, const ShellFibers* fibers = nullptr,
                        const std::string& input_checksum = {});

struct SavedBoundaryMap {
  BoundaryMap map;
  std::string input;                  // path of the dense input, as written
  std::string input_checksum;         // "" when not written
  std::optional<ShellFibers> fibers;  // present when the map was written with them
};
/// Throws IoError when the file cannot be opened, InputError naming the file and the defect
/// otherwise (including a version-1 file, which names the fix: re-run `curvefem mesh`).
SavedBoundaryMap read_boundary_map(const std::filesystem::path& path);

}  // namespace curvefem::io
