// The pipeline of `curvefem run` as a function, shared by `curvefem run` (one case) and
// `curvefem study` (many cases, in-process). cmd_run.cpp implements it.
#pragma once

#include <nlohmann/json.hpp>

#include "meshing/core/progress.hpp"
#include "meshing/core/timer.hpp"
#include "tools/curvefem/case_file.hpp"

namespace curvefem::cli {

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
/// left in spec.output_dir. Prints nothing on stdout; progress goes to `progress`.
RunOutcome run_case(const CaseSpec& spec, const RunSettings& settings, TerminalProgress& progress);

}  // namespace curvefem::cli
