// The pipeline of `curvefem run` (DESIGN.md §1) as one function composed of the stages of
// stages.hpp; shared by `curvefem run` (one case), `curvefem study` (many cases, in-process) and
// the Python module.
#pragma once

#include <nlohmann/json.hpp>

#include "meshing/core/progress.hpp"
#include "meshing/core/timer.hpp"
#include "pipeline/case_file.hpp"

namespace curvefem::pipeline {

struct RunSettings {
  int threads = 0;        ///< --threads (0 = all cores); also the curved mesher's workers
  bool paraview = false;  ///< also write open_in_paraview.py
};

struct RunOutcome {
  nlohmann::json report;  ///< report.json as written
  Timings timings;        ///< stage times, in stage order
  int exit_code = 0;      ///< 0, or 3: the curved mesh failed its validation (results written)
};

/// Runs `spec` and writes its results to spec.output_dir (atomically, report.json last). Throws
/// InputError / MeshingError / SolverError / IoError like the command; on a throw nothing new is
/// left in spec.output_dir. Prints nothing on stdout; progress goes to `progress` (may be empty).
RunOutcome run_case(const CaseSpec& spec, const RunSettings& settings,
                    const ProgressFn& progress = {});

}  // namespace curvefem::pipeline
