// The pipeline of `curvefem run` (DESIGN.md §1) as one function composed of the stages of
// stages.hpp; shared by `curvefem run` (one case), `curvefem study` (many cases, in-process) and
// the Python module.
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "meshing/core/progress.hpp"
#include "meshing/core/timer.hpp"
#include "pipeline/case_file.hpp"
#include "pipeline/stages.hpp"

namespace curvefem::pipeline {

struct RunSettings {
  int threads = 0;        ///< --threads (0 = all cores); also the curved mesher's workers
  bool paraview = false;  ///< also write open_in_paraview.py
  bool write = true;      ///< false: no output files (the results stay in RunOutcome::results)
  /// Set: the run solves on this Domain instead of loading and meshing (a curved mesh made for
  /// several runs at once, e.g. the ε levels of a study, mesh_domain_levels); it must be what
  /// mesh_domain would give for the case.
  std::shared_ptr<const Domain> domain;
};

/// The results of every stage of one run. Built in place and never moved: the Discretization and
/// the bound data refer to the Domain.
struct RunResults {
  Domain domain;
  Discretization disc;
  std::vector<LoadResult> loads;  ///< one per load case (CaseSpec::loads), in order
};

struct RunOutcome {
  nlohmann::json report;  ///< report.json as written
  Timings timings;        ///< stage times, in stage order
  int exit_code = 0;      ///< 0, or 3: the curved mesh failed its validation (results written)
  std::shared_ptr<const RunResults> results;  ///< the stage results (arrays for the Python module)
};

/// Runs `spec` and writes its results to spec.output_dir (atomically, report.json last; nothing
/// with settings.write false). Throws
/// InputError / MeshingError / SolverError / IoError like the command; on a throw nothing new is
/// left in spec.output_dir. Prints nothing on stdout; progress goes to `progress` (may be empty).
RunOutcome run_case(const CaseSpec& spec, const RunSettings& settings,
                    const ProgressFn& progress = {});

}  // namespace curvefem::pipeline
