#include "pipeline/input_floors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <unordered_map>

#include "meshing/core/position_key.hpp"

namespace curvefem::pipeline {

InputFloors input_floors(const SurfaceMesh& input, const BoundaryMap& map, const LagrangeMesh& mesh,
                         const std::vector<double>& cell_mips,
                         const std::vector<double>& cell_scaled_jacobian,
                         const check::CheckOptions& options) {
  InputFloors out;
  const auto needles = check::needle_faces(input.V, input.F, options.needle_angle_deg);
  const auto folds = check::near_fold_edges(input.V, input.F, options.fold_angle_deg);
  out.needle_faces = int(needles.size());
  out.near_fold_edges = int(folds.size());
  if (needles.empty() && folds.empty()) return out;

  // The boundary's corners by position (exact), its faces and edges by corner ids.
  const LagrangeMesh& b = map.boundary;
  std::unordered_map<PositionKey, int, PositionHash> corner_at;
  std::set<std::array<int, 3>> faces;
  std::set<std::array<int, 2>> edges;
  for (int c = 0; c < b.num_cells(); ++c) {
    std::array<int, 3> f{b.cells(c, 0), b.cells(c, 1), b.cells(c, 2)};
    for (int id : f) corner_at.emplace(position_key(b.nodes.row(id)), id);
    for (int k = 0; k < 3; ++k)
      edges.insert({std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])});
    std::sort(f.begin(), f.end());
    faces.insert(f);
  }
  auto corner_of = [&](int v) {
    const auto it = corner_at.find(position_key(input.V.row(v)));
    return it == corner_at.end() ? -1 : it->second;
  };

  auto note_edge = [&](int u, int v) {
    const double l = (input.V.row(u) - input.V.row(v)).norm();
    if (out.shortest_edge_at_kept == 0 || l < out.shortest_edge_at_kept)
      out.shortest_edge_at_kept = l;
  };
  // Kept items as sets of volume corner nodes.
  std::vector<std::vector<int>> kept;
  auto volume_node = [&](int boundary_node) {
    return boundary_node < map.boundary_node_to_volume.size()
               ? map.boundary_node_to_volume[boundary_node]
               : -1;
  };
  for (const auto& [f, angle] : needles) {
    std::array<int, 3> c{corner_of(input.F(f, 0)), corner_of(input.F(f, 1)),
                         corner_of(input.F(f, 2))};
    std::sort(c.begin(), c.end());
    if (c[0] < 0 || !faces.count(c)) continue;
    ++out.needle_faces_kept;
    if (out.kept_needle_faces.size() < 10) out.kept_needle_faces.push_back(f);
    for (int k = 0; k < 3; ++k) note_edge(input.F(f, k), input.F(f, (k + 1) % 3));
    kept.push_back({volume_node(c[0]), volume_node(c[1]), volume_node(c[2])});
  }
  for (const check::FoldEdge& e : folds) {
    const int a = corner_of(e.lo), c = corner_of(e.hi);
    if (a < 0 || c < 0 || !edges.count({std::min(a, c), std::max(a, c)})) continue;
    ++out.near_fold_edges_kept;
    if (out.kept_fold_edges.size() < 10) out.kept_fold_edges.push_back({e.lo, e.hi});
    note_edge(e.lo, e.hi);
    kept.push_back({volume_node(a), volume_node(c)});
  }
  if (kept.empty()) return out;
  if (const double box = bbox_longest_edge(input.V); box > 0)
    out.shortest_edge_at_kept_rel = out.shortest_edge_at_kept / box;

  // Tets holding every corner node of a kept item.
  std::map<int, std::vector<std::size_t>> items_of_node;
  for (std::size_t i = 0; i < kept.size(); ++i)
    for (int n : kept[i])
      if (n >= 0) items_of_node[n].push_back(i);
  // (-1: no per-tet values.)
  const long worst_mips =
      cell_mips.empty() ? -1
                        : std::max_element(cell_mips.begin(), cell_mips.end()) - cell_mips.begin();
  const long worst_sj =
      cell_scaled_jacobian.empty()
          ? -1
          : std::min_element(cell_scaled_jacobian.begin(), cell_scaled_jacobian.end()) -
                cell_scaled_jacobian.begin();
  for (int t = 0; t < mesh.num_cells(); ++t) {
    std::array<int, 4> corners{mesh.cells(t, 0), mesh.cells(t, 1), mesh.cells(t, 2),
                               mesh.cells(t, 3)};
    bool at_kept = false;
    for (int n : corners) {
      const auto it = items_of_node.find(n);
      if (it == items_of_node.end()) continue;
      for (std::size_t i : it->second)
        at_kept = at_kept || std::all_of(kept[i].begin(), kept[i].end(), [&](int m) {
                    return std::find(corners.begin(), corners.end(), m) != corners.end();
                  });
    }
    if (!at_kept) continue;
    ++out.tets_at_kept;
    if (std::size_t(t) < cell_mips.size())
      out.max_mips_at_kept = std::max(out.max_mips_at_kept, cell_mips[std::size_t(t)]);
    if (std::size_t(t) < cell_scaled_jacobian.size())
      out.min_scaled_jacobian_at_kept =
          std::min(out.min_scaled_jacobian_at_kept, cell_scaled_jacobian[std::size_t(t)]);
    out.worst_mips_tet_at_kept = out.worst_mips_tet_at_kept || t == worst_mips;
    out.worst_scaled_jacobian_tet_at_kept = out.worst_scaled_jacobian_tet_at_kept || t == worst_sj;
  }
  return out;
}

nlohmann::json input_floors_json(const InputFloors& f, const check::CheckOptions& options) {
  nlohmann::json kept_edges = nlohmann::json::array();
  for (const auto& e : f.kept_fold_edges) kept_edges.push_back({e[0], e[1]});
  return {{"what",
           "input features `curvefem check` warns of that the boundary kept as they are: the tets "
           "on them are as flat whatever the optimization does (pipeline/input_floors.hpp)"},
          {"needle_angle_deg", options.needle_angle_deg},
          {"fold_angle_deg", options.fold_angle_deg},
          {"needle_faces", f.needle_faces},
          {"needle_faces_kept", f.needle_faces_kept},
          {"kept_needle_faces", f.kept_needle_faces},
          {"near_fold_edges", f.near_fold_edges},
          {"near_fold_edges_kept", f.near_fold_edges_kept},
          {"kept_fold_edges", kept_edges},
          {"tets_at_kept", f.tets_at_kept},
          {"shortest_edge_at_kept_rel",
           f.shortest_edge_at_kept > 0 ? nlohmann::json(f.shortest_edge_at_kept_rel) : nullptr},
          {"max_mips_at_kept", f.tets_at_kept > 0 ? nlohmann::json(f.max_mips_at_kept) : nullptr},
          {"min_scaled_jacobian_at_kept",
           f.tets_at_kept > 0 ? nlohmann::json(f.min_scaled_jacobian_at_kept) : nullptr},
          {"worst_mips_tet_at_kept", f.worst_mips_tet_at_kept},
          {"worst_scaled_jacobian_tet_at_kept", f.worst_scaled_jacobian_tet_at_kept}};
}

std::string merge_hint(const InputFloors& f, double eps_rel) {
  if (!(f.worst_mips_tet_at_kept || f.worst_scaled_jacobian_tet_at_kept) ||
      !(f.shortest_edge_at_kept_rel > 0) || !(f.shortest_edge_at_kept_rel < eps_rel))
    return {};
  // Two significant digits, rounded up above the edge (an edge equal to L is not merged).
  const double l = 1.05 * f.shortest_edge_at_kept_rel;
  const double unit = std::pow(10.0, std::floor(std::log10(l)) - 1);
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "the mesh's worst tet is on an input needle or fold the boundary kept as it is "
                "(report.json input_floors), whose shortest edge is %.3g of the bbox: "
                "`--merge-short-edges %.2g` merges edges up to that length first (the map is then "
                "to the repaired surface)",
                f.shortest_edge_at_kept_rel, std::ceil(l / unit) * unit);
  return buf;
}

}  // namespace curvefem::pipeline
