#include "pipeline/report_json.hpp"

#include <algorithm>
#include <cmath>

namespace curvefem::pipeline {

nlohmann::json defects_json(const std::vector<check::Defect>& defects) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& d : defects)
    a.push_back({{"kind", d.kind},
                 {"count", d.count},
                 {"id_kind", d.id_kind},
                 {"ids", d.ids},
                 {"message", d.message}});
  return a;
}

nlohmann::json merge_summary_json(const check::MergeShortEdgesResult& r, double length_rel,
                                  double max_length) {
  return {{"merge_short_edges_rel", length_rel},
          {"max_length", max_length},
          {"candidates", r.candidates},
          {"merged", r.merged.size()},
          {"left", r.refused},
          {"max_moved", r.max_moved}};
}

nlohmann::json merge_map_json(const check::MergeShortEdgesResult& r) {
  nlohmann::json pairs = nlohmann::json::array();
  for (const check::MergedEdge& e : r.merged)
    pairs.push_back({{"removed", e.removed}, {"kept", e.kept}, {"length", e.length}});
  return {{"pairs", pairs}, {"vertex_map", r.vertex_map}, {"face_origin", r.face_origin}};
}

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
  j["orientable"] = r.orientable;
  j["faces_to_flip"] = r.faces_to_flip;
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
  j["self_intersections_mesh_api"] = r.self_intersections_mesh_api;
  j["self_intersecting_pairs"] = r.self_intersecting_pairs;
  j["volume_bounded"] = r.volume_bounded;
  j["bbox_longest_edge"] = r.bbox_longest_edge;
  j["acceptable"] = r.acceptable;
  j["time_s"] = r.time_s;
  j["defects"] = defects_json(r.defects);
  j["warnings"] = defects_json(r.warnings);
  return j;
}

nlohmann::json timings_json(const Timings& timings) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [stage, seconds] : timings.stages()) j[stage] = seconds;
  return j;
}

nlohmann::ordered_json curved_mesh_stats_json(const meshing::curved::CurvedMeshStats& stats,
                                              const meshing::curved::CurvedMeshOptions& options) {
  nlohmann::ordered_json refused = nlohmann::ordered_json::object();
  for (const auto& [why, n] : stats.coarsen_rejections) refused[why] = n;
  nlohmann::ordered_json coarsen_seconds = nlohmann::ordered_json::object();
  for (const auto& [name, t] : stats.coarsen_seconds) coarsen_seconds[name] = t;
  return {{"input_vertices", stats.input_vertices},
          {"input_faces", stats.input_faces},
          {"order", options.order},
          {"eps_rel", options.eps_rel},
          {"feature_edges", stats.feature_edges},
          {"small_features_dropped",
           {{"min_size_eps", options.feature_min_size},
            {"curves", stats.small_feature_curves},
            {"edges", stats.small_feature_edges}}},
          {"feature_ends_trimmed",
           {{"length_eps", options.feature_end_trim},
            {"ends", stats.trimmed_feature_ends},
            {"edges", stats.trimmed_feature_edges}}},
          {"frozen_vertices", stats.frozen_vertices},
          {"slab_tets", stats.slab_tets},
          {"thickened_vertices", stats.thickened_vertices},
          {"interior_tets", stats.interior_tets},
          {"outer_slab_tets", stats.outer_slab_tets},
          {"outer_raised_vertices", stats.outer_raised_vertices},
          {"outer_lowered_vertices", stats.outer_lowered_vertices},
          {"exterior_tets", stats.exterior_tets},
          {"shell_prisms", stats.shell_faces},
          {"coarse_faces", stats.coarse_faces},
          {"coarsening",
           {{"start_faces", stats.coarsen_start_faces},
            {"linear_phase_faces", stats.linear_phase_faces},
            {"linear_phase_seconds", stats.linear_phase_seconds},
            {"linear_phase_concurrent", stats.linear_phase_concurrent},
            {"collapses", stats.coarsen_collapses},
            {"flips", stats.coarsen_flips},
            {"pillar_rotations", stats.coarsen_rotations},
            {"thickness_growths", stats.coarsen_zooms},
            {"zoom_passes", options.shell_zoom_passes},
            {"pillar_cos_bound", options.shell_pillar_cos},
            {"pillar_cos_relative", options.shell_pillar_cos_relative},
            {"pillar_cos_relaxed_pillars", stats.coarsen_relaxed_pillars},
            {"min_pillar_cos_bound", stats.coarsen_min_section_bound},
            {"pans", stats.coarsen_pans},
            {"splits", stats.coarsen_splits},
            {"chain_collapses", stats.coarsen_chain_collapses},
            {"curved_aware", stats.curved_coarsening},
            {"curved_attempts", stats.curved_attempts},
            {"strict_vertices", stats.strict_vertices},
            {"curved_widened", stats.curved_widened},
            {"curved_repairs", stats.curved_repairs},
            {"repair_splits", stats.repair_splits},
            {"repair_failures", stats.repair_failures},
            {"snapped_vertices", stats.snapped_vertices},
            {"chain_max_distance_rel", stats.chain_max_distance_rel},
            {"median_half_thickness_rel", stats.coarse_median_thickness_rel},
            {"min_half_thickness_rel", stats.coarse_min_thickness_rel},
            {"collapses_refused", refused},
            {"shape_slack", options.shape_slack},
            {"seconds", coarsen_seconds}}},
          {"singular_vertices", stats.singular_vertices},
          {"beveled_faces", stats.beveled_faces},
          {"thin_refinement",
           {{"ratio", options.thin_refine_ratio},
            {"refined_input_faces", stats.thin_refined_faces},
            {"bisections", stats.thin_splits},
            {"shape_refusals", stats.thin_shape_refusals},
            {"thin_edges_before", stats.thin_edges_before},
            {"thin_edges_after", stats.thin_edges_after},
            {"max_ratio_before", stats.thin_max_ratio_before},
            {"max_ratio_after", stats.thin_max_ratio_after},
            {"fallback", stats.thin_fallback}}},
          {"roundtrip_fallback", stats.roundtrip_fallback},
          {"shape_refinement",
           {{"min_edge_eps", options.shape_refine},
            {"spike_angle_deg", options.shape_refine_spike_angle},
            {"refined_input_faces", stats.shape_refined_faces},
            {"bisections", stats.shape_splits},
            {"feature_bisections", stats.shape_feature_splits},
            {"poor_faces_before", stats.shape_poor_before},
            {"poor_faces_after", stats.shape_poor_after},
            {"spike_faces", stats.shape_spike_faces},
            {"budget_reached", stats.shape_budget_reached}}},
          {"shell_section_verified", stats.shell_section_verified},
          {"shell_non_section_prisms", stats.shell_non_section_prisms},
          {"shell_min_pillar_cos", stats.shell_min_pillar_cos},
          {"shell_reference_collapsed_faces", stats.shell_reference_collapsed_faces},
          {"faces_fully_curved", stats.faces_fully_curved},
          {"faces_blended", stats.faces_blended},
          {"faces_linear", stats.faces_linear},
          {"curve_refused",
           {{"certificate", stats.curve_refused_certificate},
            {"distance", stats.curve_refused_distance},
            {"deferred_outer", stats.curve_deferred_outer},
            {"deferred_undecided", stats.curve_deferred_undecided}}},
          {"faces_recurved", stats.faces_recurved},
          {"faces_lowered_for_quality", stats.faces_lowered_for_quality},
          {"embedding_repair",
           {{"pairs_before", stats.embedding_pairs_before},
            {"pairs_after", stats.embedding_pairs_after},
            {"rounds", stats.embedding_rounds},
            {"faces_lowered", stats.faces_lowered_for_embedding}}},
          {"quality_floor", options.curve_quality_floor},
          {"distortion_repair",
           {{"floor", options.curve_distortion_floor},
            {"faces_below_before", stats.distorted_faces_before},
            {"faces_below_after", stats.distorted_faces_after},
            {"folded_before", stats.folded_faces_before},
            {"folded_after", stats.folded_faces_after},
            {"below_after_needing_full_curving", stats.distorted_needed_after},
            {"faces_lowered", stats.faces_lowered_for_distortion}}},
          {"faces_sheared", stats.faces_sheared},
          {"fiber_misses", stats.fiber_misses},
          {"linear_max_distance_rel", stats.linear_max_distance_rel},
          {"distance_points", stats.distance_points},
          {"optimize", optimize_json(stats.optimize)}};
}

nlohmann::ordered_json optimize_json(const meshing::curved::OptimizeStats& s) {
  return {
      {"sweeps", s.sweeps},
      {"movable_vertices", s.movable_vertices},
      {"visits", s.visits},
      {"moves", s.moves},
      {"rejected_by_certificate", s.rejected_by_certificate},
      {"nodes",
       {{"sweeps", s.node_sweeps},
        {"movable", s.movable_nodes},
        {"visits", s.node_visits},
        {"moves", s.node_moves}}},
      {"worst",
       {{"sweeps", s.worst_sweeps},
        {"movable", s.worst_movable},
        {"visits", s.worst_visits},
        {"moves", s.worst_moves},
        {"min_scaled_jacobian_before", s.worst_sj_before},
        {"min_scaled_jacobian_after", s.worst_sj_after},
        {"mips_movable", s.worst_mips_movable},
        {"mips_visits", s.worst_mips_visits},
        {"mips_moves", s.worst_mips_moves},
        {"max_mips_before", s.worst_mips_before},
        {"max_mips_after", s.worst_mips_after},
        {"mean_mips_movable", s.mean_mips_movable},
        {"mean_mips_visits", s.mean_mips_visits},
        {"mean_mips_moves", s.mean_mips_moves},
        {"mean_mips_before", s.mean_mips_before},
        {"mean_mips_after", s.mean_mips_after},
        {"mean_mips_variation_guard", s.mean_variation_guard},
        {"seconds", s.worst_seconds}}},
      {"energy_before", {{"mean", s.mean_energy_before}, {"max", s.max_energy_before}}},
      {"energy_after", {{"mean", s.mean_energy_after}, {"max", s.max_energy_after}}},
      {"energy", "conformal AMIPS against the regular tet, mean over the order-k lattice"},
      {"seconds", s.seconds},
      {"interior_flips",
       {{"flips", s.flips.count},
        {"tets", {{"before", s.flips.tets_before}, {"after", s.flips.tets_after}}},
        {"energy_before",
         {{"mean", s.flips.mean_energy_before}, {"max", s.flips.max_energy_before}}},
        {"energy_after", {{"mean", s.flips.mean_energy_after}, {"max", s.flips.max_energy_after}}},
        {"seconds", s.flips.seconds}}},
      {"curved_edits",
       {{"passes", s.edits.passes},
        {"collapses", s.edits.collapses},
        {"flips", s.edits.flips},
        {"splits", s.edits.splits},
        {"mean_flips",
         {{"flips", s.edits.mean_flips},
          {"mean_mips_before", s.edits.mean_mips_before},
          {"mean_mips_after", s.edits.mean_mips_after}}},
        {"attempted", s.edits.attempted},
        {"replayed", s.edits.replayed},
        {"energy_prechecked", s.edits.energy_prechecked},
        {"rejected",
         {{"certificate", s.edits.rejected_certificate},
          {"energy", s.edits.rejected_energy},
          {"topology", s.edits.rejected_topology},
          {"locked_cell", s.edits.rejected_locked}}},
        {"tets", {{"before", s.edits.cells_before}, {"after", s.edits.cells_after}}},
        {"targets", {{"before", s.edits.targets_before}, {"after", s.edits.targets_after}}},
        {"energy_before",
         {{"mean", s.edits.mean_energy_before}, {"max", s.edits.max_energy_before}}},
        {"energy_after", {{"mean", s.edits.mean_energy_after}, {"max", s.edits.max_energy_after}}},
        {"seconds", s.edits.seconds}}}};
}

// Per tet, from the independent validation (mesh.vtu, run's volume.vtu; for ParaView).
std::vector<Field> curved_validation_cell_fields(const meshing::curved::CurvedValidation& v) {
  return {
      {"certified", 1, std::vector<double>(v.cell_certificate.begin(), v.cell_certificate.end())},
      {"scaled_jacobian", 1, v.cell_scaled_jacobian},
      {"curved_mips", 1, v.cell_mips},
      {"jacobian_ratio", 1, v.cell_jacobian_ratio},
      {"distortion_d2", 1, v.cell_d2},
      {"distortion_d3", 1, v.cell_d3}};
}

nlohmann::ordered_json curved_validation_json(const meshing::curved::CurvedValidation& v,
                                              double eps_rel) {
  nlohmann::ordered_json by_tag = nlohmann::ordered_json::object();
  for (const auto& [tag, q] : v.quality_by_tag)
    by_tag[tag == 1   ? "slab"
           : tag == 2 ? "interior"
           : tag == 3 ? "outer_slab"
           : tag == 4 ? "exterior"
                      : std::to_string(tag)] = {
        {"tets", q.tets},
        {"min_scaled_jacobian", q.min_scaled_jacobian},
        {"tets_scaled_jacobian_below_0.01", q.tets_sj_below_1e2},
        {"tets_scaled_jacobian_below_0.001", q.tets_sj_below_1e3},
        {"mean_mips", q.mean_mips},
        {"max_mips", q.max_mips},
        {"min_jacobian_ratio", q.min_jacobian_ratio},
        {"max_d2", q.max_d2},
        {"mean_d2", q.mean_d2},
        {"max_d3", q.max_d3},
        {"mean_d3", q.mean_d3}};
  const double over_local_eps =
      eps_rel > 0 ? std::max(v.max_scaled_distance_rel, v.points_max_scaled_distance_rel) / eps_rel
                  : 0.0;
  return {{"valid", v.valid(eps_rel)},
          {"tets", v.tets},
          {"min_jacobian_certified", v.certified()},
          {"non_positive_tets", v.non_positive_tets},
          {"undecided_tets", v.undecided_tets},
          {"first_bad_tet", v.first_bad_tet},
          {"min_scaled_jacobian", v.min_scaled_jacobian},
          {"tets_scaled_jacobian_below_0.01", v.tets_sj_below_1e2},
          {"tets_scaled_jacobian_below_0.001", v.tets_sj_below_1e3},
          {"mean_mips", v.mean_mips},
          {"max_mips", v.max_mips},
          {"distortion",
           {{"definition",
             "per tet, sampled: jacobian_ratio = min/max det J; d2 = |D2F| |DF^-1|, d3 = |D3F| "
             "|DF^-1| (reference tet; 0 when straight), element_distortion.hpp"},
            {"min_jacobian_ratio", v.min_jacobian_ratio},
            {"max_d2", v.max_d2},
            {"mean_d2", v.mean_d2},
            {"max_d3", v.max_d3},
            {"mean_d3", v.mean_d3}}},
          {"quality_by_tag", by_tag},
          {"boundary_faces", v.boundary_faces},
          {"boundary_faces_missing", v.boundary_faces_missing},
          {"boundary_faces_extra", v.boundary_faces_extra},
          {"boundary_node_mismatches", v.boundary_node_mismatches},
          {"exterior", v.exterior},
          {"exterior_boundary_faces", v.exterior_boundary_faces},
          {"exterior_faces_off_box", v.exterior_faces_off_box},
          {"boundary_subdivision", v.subdivision},
          {"boundary_self_intersections", v.boundary_self_intersections},
          {"boundary_min_area_ratio", v.min_boundary_area_ratio},
          {"boundary_faces_folded", v.boundary_faces_folded},
          {"boundary_faces_area_ratio_below_0.1", v.boundary_faces_distorted},
          {"boundary_limits",
           {{"what",
             "bounds for straight tets on the boundary's corner triangles "
             "(meshing/curved/boundary_limits.hpp)"},
            {"mips_floor", std::isfinite(v.boundary_limits.mips_floor)
                               ? nlohmann::ordered_json(v.boundary_limits.mips_floor)
                               : nlohmann::ordered_json(nullptr)},
            {"mips_floor_face", v.boundary_limits.mips_floor_face},
            {"mips_floor_at",
             {v.boundary_limits.mips_floor_at.x(), v.boundary_limits.mips_floor_at.y(),
              v.boundary_limits.mips_floor_at.z()}},
            {"faces_mips_floor_above_1e4", v.boundary_limits.faces_mips_floor_above_1e4},
            {"sj_ceiling", v.boundary_limits.sj_ceiling},
            {"sj_ceiling_face", v.boundary_limits.sj_ceiling_face},
            {"faces_sj_ceiling_below_0.01", v.boundary_limits.faces_sj_ceiling_below_1e2},
            {"faces_sj_ceiling_below_0.001", v.boundary_limits.faces_sj_ceiling_below_1e3},
            {"min_dihedral_deg", v.boundary_limits.min_dihedral_deg},
            {"edges_sj_ceiling_below_0.01", v.boundary_limits.edges_sj_ceiling_below_1e2},
            {"edges_sj_ceiling_below_0.001", v.boundary_limits.edges_sj_ceiling_below_1e3}}},
          {"unmapped_vertices", v.unmapped_vertices},
          {"max_distance_rel", v.max_distance_rel},
          {"max_distance_vertex", v.max_distance_vertex},
          {"distance_points", v.distance_points},
          {"distance_points_bad", v.bad_distance_points},
          {"distance_points_max_distance_rel", v.points_max_distance_rel},
          {"distance_points_max_distance_point", v.points_max_distance_point},
          {"eps_rel", eps_rel},
          {"eps_field", v.eps_field},
          {"max_distance_over_local_eps", over_local_eps},
          {"max_distance_over_local_eps_vertex", v.max_scaled_distance_vertex},
          {"feature_edges", v.feature_edges},
          {"features_off_boundary_edges", v.features_off_edges},
          {"first_feature_off", v.first_feature_off},
          {"input_faces_orientation_checked", v.input_faces_checked},
          {"flipped_input_faces", v.flipped_input_faces},
          {"seconds", v.seconds}};
}

}  // namespace curvefem::pipeline
