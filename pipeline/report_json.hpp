// JSON forms of the library's reports: one per stats struct (report.json of every command).
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "meshing/check/check_surface.hpp"
#include "meshing/check/merge_short_edges.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/curved/curved_mesher.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/curved/optimize.hpp"

namespace curvefem::pipeline {

/// A CheckReport's defects or warnings as an array of {kind, count, id_kind, ids, message}.
nlohmann::json defects_json(const std::vector<check::Defect>& defects);

/// Every field of a CheckReport, defects and warnings as defects_json arrays.
nlohmann::json check_report_json(const check::CheckReport& report);

/// A repair by check::merge_short_edges (`--merge-short-edges`, meshing.merge_short_edges):
/// merge_short_edges_rel (the length asked, × the bbox), max_length, candidates, merged, left,
/// max_moved.
nlohmann::json merge_summary_json(const check::MergeShortEdgesResult& r, double length_rel,
                                  double max_length);
/// Its vertex map file: pairs [{removed, kept, length}], vertex_map, face_origin.
nlohmann::json merge_map_json(const check::MergeShortEdgesResult& r);

/// {"stage": seconds, ...} in stage order.
nlohmann::json timings_json(const Timings& timings);

/// OptimizeStats of the curved mesher's optimization stage.
nlohmann::ordered_json optimize_json(const meshing::curved::OptimizeStats& s);

/// What the curved mesher reports about its own run (`curvefem mesh` report.json, and
/// "meshing" of `curvefem run`): counts per stage, coarsening, thin refinement, curving,
/// optimization. Validation and the exterior box are the callers' (they differ in form).
nlohmann::ordered_json curved_mesh_stats_json(const meshing::curved::CurvedMeshStats& stats,
                                              const meshing::curved::CurvedMeshOptions& options);

/// The independent validation of a curved mesh (report.json "validation"), judged against ε.
nlohmann::ordered_json curved_validation_json(const meshing::curved::CurvedValidation& v,
                                              double eps_rel);

/// Per tet, from the independent validation (mesh.vtu, run's volume.vtu; for ParaView).
std::vector<Field> curved_validation_cell_fields(const meshing::curved::CurvedValidation& v);

}  // namespace curvefem::pipeline
