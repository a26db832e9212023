// The shell's applications behind `curvefem shell` options (thesis §4.4–4.5): each runs on a
// built shell or on the input, writes its files into the command's output folder and returns
// its report block, with the checks made by code independent of the construction
// (meshing/check: CGAL distances and exact intersection tests).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/nested_cages.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::cli {

/// --displacement-map L on `shell` (built on `surface`): displacement_map.txt, cage.obj,
/// displaced.obj; report block `displacement_map`.
nlohmann::ordered_json run_displacement_map(const meshing::shell::Shell& shell,
                                            const SurfaceMesh& surface, int level,
                                            const StagedOutputDir& out);

/// True when the block says every sample mapped and every rebuilt vertex is on the input and on
/// its fiber (what the command's exit code requires).
bool displacement_map_ok(const nlohmann::ordered_json& block);

/// --cages K: cage_1.obj … cage_K.obj; report block `nested_cages` (per layer: faces, the top
/// surface's self-intersections before and after shrinking, the shell's verification; across
/// layers: intersecting pairs between every two layers, nesting, the maps' roundtrip).
/// Throws MeshingError as build_nested_cages does.
nlohmann::ordered_json run_nested_cages(const SurfaceMesh& input,
                                        const meshing::shell::NestedCageOptions& options,
                                        const StagedOutputDir& out);

/// True when the block says every layer is embedded, apart from the others, nested, and the
/// maps sampled roundtrip.
bool nested_cages_ok(const nlohmann::ordered_json& block);

/// The tile of --texture TILE: a built-in name or an OBJ file, checked to lie in the unit prism
/// (InputError otherwise).
SurfaceMesh load_tile(const std::string& spec);
/// --texture on `shell` (built on `surface`): textured.obj, report block `geometric_texture`
/// (exact: the copies' self-intersecting pairs and pairs with the input; CGAL distance to the
/// input).
nlohmann::ordered_json run_geometric_texture(const meshing::shell::Shell& shell,
                                             const SurfaceMesh& surface, const SurfaceMesh& tile,
                                             const std::string& tile_name,
                                             const StagedOutputDir& out);
bool geometric_texture_ok(const nlohmann::ordered_json& block);

}  // namespace curvefem::cli
