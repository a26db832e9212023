// Triangle surface from a Gmsh MSH file: the 3-node triangles (type 2), ordered by element id;
// physical tags become face tags and dimension-2 physical names become tag names. Only nodes used
// by the triangles are kept, in their file order.
#include <algorithm>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/io/msh_parser.hpp"
#include "meshing/io/surface_io.hpp"
#include "meshing/io/text_scanner.hpp"

namespace curvefem::io {

SurfaceMesh read_msh_surface(const std::filesystem::path& path) {
  const std::string file = path.string();
  const detail::MshData msh = detail::parse_msh(path);

  struct Tri {
    long long id;
    int nodes[3];  // rows of msh.nodes
    int tag;
  };
  std::vector<Tri> tris;
  std::set<int> other_types;
  for (const auto& block : msh.blocks) {
    if (block.gmsh_type != 2) {
      if (!block.element_ids.empty()) other_types.insert(block.gmsh_type);
      continue;
    }
    for (std::size_t e = 0; e < block.element_ids.size(); ++e) {
      Tri t{block.element_ids[e], {0, 0, 0}, block.physical_tags[e]};
      for (int c = 0; c < 3; ++c) t.nodes[c] = msh.node_index.at(block.node_ids[3 * e + c]);
      tris.push_back(t);
    }
  }
  if (tris.empty()) {
    std::string types;
    for (int t : other_types) types += (types.empty() ? "" : ", ") + std::to_string(t);
    throw InputError(
        "no 3-node triangles (Gmsh element type 2) in the file" +
            (types.empty() ? std::string() : " (element types present: " + types + ")"),
        {.file = file});
  }
  // File order of the faces = element id order (the writers number faces that way).
  std::stable_sort(tris.begin(), tris.end(),
                   [](const Tri& a, const Tri& b) { return a.id < b.id; });

  // Keep the used nodes, in file order.
  std::vector<int> new_index(static_cast<std::size_t>(msh.nodes.rows()), -1);
  for (const Tri& t : tris)
    for (int n : t.nodes) new_index[static_cast<std::size_t>(n)] = 0;
  std::vector<double> xyz;
  int next = 0;
  for (Eigen::Index r = 0; r < msh.nodes.rows(); ++r) {
    if (new_index[static_cast<std::size_t>(r)] < 0) continue;
    new_index[static_cast<std::size_t>(r)] = next++;
    xyz.insert(xyz.end(), {msh.nodes(r, 0), msh.nodes(r, 1), msh.nodes(r, 2)});
  }
  std::vector<int> tri;
  std::vector<int> tags;
  tri.reserve(tris.size() * 3);
  bool tagged = false;
  for (const Tri& t : tris) {
    for (int n : t.nodes) tri.push_back(new_index[static_cast<std::size_t>(n)]);
    tags.push_back(t.tag);
    tagged |= t.tag != 0;
  }
  if (!tagged) tags.clear();
  SurfaceMesh mesh = detail::make_surface(xyz, tri, tags, file);
  if (tagged) {
    std::set<int> present(tags.begin(), tags.end());
    for (const auto& [key, name] : msh.physical_names_by_dim)
      if (key.first == 2 && present.count(key.second)) mesh.tag_names[key.second] = name;
  }
  return mesh;
}

}  // namespace curvefem::io
