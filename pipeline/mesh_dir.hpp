// Mesh reuse (case key geometry.mesh_dir; issue 23): a curved mesh saved with its boundary map φ
// and the fibers of its coarse shell (φ⁻¹, meshing/core/shell_fibers.hpp) is loaded instead of
// being meshed again, so new physics and boundary conditions run on it. A `curvefem mesh` output
// and the output of a curved `curvefem run` both hold what it needs: mesh.msh (order k, Gmsh 4.1)
// and boundary_map.json (φ, the fibers, the input's path and the checksum of its bytes). A changed
// input (another checksum) is refused: the map would no longer describe it.
#pragma once

#include <filesystem>
#include <string>

#include "meshing/core/boundary_map.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/shell_fibers.hpp"
#include "pipeline/stages.hpp"

namespace curvefem::pipeline {

/// FNV-1a (64 bits) of a file's bytes, as 16 hex digits. IoError when it cannot be read.
std::string file_checksum(const std::filesystem::path& path);

/// Writes mesh.msh and boundary_map.json into `dir` (a folder being staged; `input` is the path
/// recorded for the dense input: absolute, or relative to `dir`).
void save_mesh_dir(const std::filesystem::path& dir, const LagrangeMesh& mesh,
                   const BoundaryMap& map, const ShellFibers& fibers, const std::string& input,
                   const std::string& input_checksum);

/// The Domain of a saved curved mesh (spec.mesh_dir): the mesh, φ, the fibers and the input read
/// from the recorded path, whose checksum must match (InputError naming the file otherwise), and
/// — with meshing.validate — the independent validation run again on them.
Domain load_mesh_dir(const CaseSpec& spec, const StageContext& ctx = {});

/// A curved Domain's independent validation at eps_rel and its map round trip (mesh_validity.hpp):
/// report "validation", "valid", the per-tet quality fields. The mesh, map, fibers and input must
/// be set.
void validate_domain(Domain& d, double eps_rel);

}  // namespace curvefem::pipeline
