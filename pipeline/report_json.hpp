// JSON forms of the library's reports: one per stats struct (report.json of every command).
#pragma once

#include <nlohmann/json.hpp>

#include "meshing/check/check_surface.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/curved/curved_validate.hpp"
#include "meshing/curved/optimize.hpp"

namespace curvefem::pipeline {

/// Every field of a CheckReport, defects as an array of {kind, count, id_kind, ids, message}.
nlohmann::json check_report_json(const check::CheckReport& report);

/// {"stage": seconds, ...} in stage order.
nlohmann::json timings_json(const Timings& timings);

/// OptimizeStats of the curved mesher's optimization stage.
nlohmann::ordered_json optimize_json(const meshing::curved::OptimizeStats& s);

/// The independent validation of a curved mesh (report.json "validation"), judged against ε.
nlohmann::ordered_json curved_validation_json(const meshing::curved::CurvedValidation& v,
                                              double eps_rel);

/// Per tet, from the independent validation (mesh.vtu, run's volume.vtu; for ParaView).
std::vector<Field> curved_validation_cell_fields(const meshing::curved::CurvedValidation& v);

}  // namespace curvefem::pipeline
