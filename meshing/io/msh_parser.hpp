// Internal: a bounds-checked parser of Gmsh MSH 2.2 and 4.1 files (ascii and binary), shared by
// the surface reader and the volume reader. Any defect throws InputError with file and line (ascii)
// or byte offset (binary).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace curvefem::io::detail {

struct MshElementBlock {
  int gmsh_type = 0;   ///< Gmsh element type number
  int dim = 0;         ///< 0..3
  int entity_tag = 0;  ///< elementary entity (2.2: elementary tag of each element's block)
  int nodes_per_element = 0;
  std::vector<long long> element_ids;
  std::vector<long long> node_ids;  ///< flattened, nodes_per_element per element (file ids)
  std::vector<int> physical_tags;   ///< one per element; 0 = none
};

struct MshData {
  double version = 0.0;
  bool binary = false;
  Eigen::MatrixXd nodes;                          ///< #N × 3, in order of appearance
  std::unordered_map<long long, int> node_index;  ///< file node id → row of `nodes`
  std::vector<MshElementBlock> blocks;
  std::map<int, std::string> physical_names;  ///< physical tag → name (highest dim on a clash)
  std::map<std::pair<int, int>, std::string> physical_names_by_dim;  ///< (dim, tag) → name
};

/// Parses the whole file (MSH 2.x or 4.1, ascii or binary, either byte order). Nodes referenced by
/// elements are checked to exist; unknown sections are skipped; all counts are checked against the
/// remaining file size before anything is allocated.
MshData parse_msh(const std::filesystem::path& path);

/// Nodes per element of a Gmsh element type (the format's table); -1 for unknown types.
int gmsh_nodes_per_element(int gmsh_type);
/// Dimension (0..3) of a Gmsh element type; -1 for unknown types.
int gmsh_element_dim(int gmsh_type);

}  // namespace curvefem::io::detail
