#include "tools/curvefem/report_json.hpp"

namespace curvefem::cli {

nlohmann::json check_report_json(const check::CheckReport& r) {
  nlohmann::json j;
  j["vertices"] = r.vertices;
  j["faces"] = r.faces;
  j["referenced_vertices"] = r.referenced_vertices;
  j["unreferenced_vertices"] = r.unreferenced_vertices;
  j["components"] = r.components;
  j["closed"] = r.closed;
  j["boundary_edges"] = r.boundary_edges;
  j["edge_manifold"] = r.edge_manifold;
  j["non_manifold_edges"] = r.non_manifold_edges;
  j["vertex_manifold"] = r.vertex_manifold;
  j["non_manifold_vertices"] = r.non_manifold_vertices;
  j["consistently_oriented"] = r.consistently_oriented;
  j["inconsistent_edges"] = r.inconsistent_edges;
  j["orientation_sign"] = r.orientation_sign;
  j["signed_volume"] = r.signed_volume;
  j["euler_characteristic"] = r.euler_characteristic;
  j["genus"] = r.genus;
  j["degenerate_faces"] = r.degenerate_faces;
  j["min_angle_deg"] = r.min_angle_deg;
  j["max_angle_deg"] = r.max_angle_deg;
  j["duplicate_vertices"] = r.duplicate_vertices;
  j["duplicate_faces"] = r.duplicate_faces;
  j["self_intersections_checked"] = r.self_intersections_checked;
  j["self_intersecting_pairs"] = r.self_intersecting_pairs;
  j["volume_bounded"] = r.volume_bounded;
  j["bbox_longest_edge"] = r.bbox_longest_edge;
  j["acceptable"] = r.acceptable;
  j["time_s"] = r.time_s;
  j["defects"] = nlohmann::json::array();
  for (const auto& d : r.defects)
    j["defects"].push_back({{"kind", d.kind},
                            {"count", d.count},
                            {"id_kind", d.id_kind},
                            {"ids", d.ids},
                            {"message", d.message}});
  return j;
}

nlohmann::json timings_json(const Timings& timings) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [stage, seconds] : timings.stages()) j[stage] = seconds;
  return j;
}

}  // namespace curvefem::cli
