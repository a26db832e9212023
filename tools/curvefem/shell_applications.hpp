// The shell's applications behind `curvefem shell` options (thesis §4.4–4.5): each runs on a
// built shell or on the input, writes its files into the command's output folder and returns
// its report block, with the checks made by code independent of the construction
// (meshing/check: CGAL distances and exact intersection tests).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/bevel.hpp"
#include "meshing/shell/boolean.hpp"
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

/// --boolean OP --with B: the operands and the corefined result the shell is built on.
struct BooleanInput {
  SurfaceMesh a, b;
  meshing::shell::BooleanResult result;
  std::string operation;
  int self_intersecting_pairs = 0;  ///< of the rounded result (exact); must be 0 to go on
  double seconds = 0;
};
/// Reads B, corefines, checks the rounded result; MeshingError when it self-intersects.
BooleanInput prepare_boolean(const SurfaceMesh& a, const std::string& b_path,
                             const std::string& operation);

/// After the shell is built on the result (beveled.surface) and simplified: carries a smooth test
/// field of each operand (different per operand) from the operands onto the result and through P
/// onto the coarse middle surface; writes result.vtu and remeshed.vtu (point data `field`,
/// `operand`) and returns the report block `boolean`: sizes, and the checks (every coarse
/// vertex's image on the result lies on its operand, CGAL distance; the carried value against the
/// operand's field at that point).
nlohmann::ordered_json run_boolean_transfer(const BooleanInput& in,
                                            const meshing::shell::Shell& shell,
                                            const meshing::shell::BeveledSurface& surface,
                                            const StagedOutputDir& out);
bool boolean_ok(const nlohmann::ordered_json& block);

}  // namespace curvefem::cli
