// boundary_map.json: the BoundaryMap φ of a `mesh` output (DESIGN.md §2), self-contained: the
// curved boundary triangles with their own node copy (and the volume node each one is), and for
// every input vertex its boundary triangle and (u, v) in it. Doubles are written with round-trip
// precision, so a read map equals the written one bit for bit.
#pragma once

#include <filesystem>
#include <string>

#include "meshing/core/boundary_map.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::cli {

/// `shell` (optional): the coarse shell the boundary was curved in (φ⁻¹ = its projection).
void write_boundary_map(const std::filesystem::path& path, const BoundaryMap& map,
                        const std::string& input, const meshing::shell::Shell* shell = nullptr);

struct SavedBoundaryMap {
  BoundaryMap map;
  std::string input;  // absolute path of the dense input
  bool has_shell = false;
  meshing::shell::Shell shell;  // valid when has_shell
};
/// Throws InputError naming the file and the defect.
SavedBoundaryMap read_boundary_map(const std::filesystem::path& path);

}  // namespace curvefem::cli
