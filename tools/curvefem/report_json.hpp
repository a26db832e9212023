// JSON forms of the library's reports (nlohmann-json stays in tools/, STYLE.md).
#pragma once

#include <nlohmann/json.hpp>

#include "meshing/check/check_surface.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::cli {

/// Every field of a CheckReport, defects as an array of {kind, count, id_kind, ids, message}.
nlohmann::json check_report_json(const check::CheckReport& report);

/// {"stage": seconds, ...} in stage order.
nlohmann::json timings_json(const Timings& timings);

}  // namespace curvefem::cli
