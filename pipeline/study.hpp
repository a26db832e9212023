// Convergence studies (`curvefem study`, `curvefem.study` in Python; format in cases/README.md,
// "Studies"): every run of a study (study_file.hpp) goes through run_case in this process into
// DIR/runs/<name>/; then DIR/study.csv (one row per run), DIR/study.gp + DIR/study.png (log-log
// error vs DOFs drawn by gnuplot, one curve per error and combination of the non-refined keys,
// fitted rates in the legend) and DIR/study.json (the resolved study, every run, the fitted rates;
// written last). All of it is staged in a hidden folder and moved into DIR at the end; DIR/runs is
// replaced as a whole. A run that fails is a row with its status and message and the others go
// on. Curved runs that differ only in meshing.eps share one shell and coarsening
// (mesh_domain_levels). Prints nothing: progress and per-run results go to the callbacks.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "meshing/core/progress.hpp"
#include "pipeline/study_file.hpp"

namespace curvefem::pipeline {

/// An error field of report.json that a study tabulates; `plotted` ones are drawn in study.png.
struct StudyErrorField {
  const char* key;    ///< report.json key, e.g. "l2_error"
  const char* label;  ///< legend / summary label, e.g. "L2"
  bool plotted;
  int dash, point;  ///< gnuplot dash and point type
};
std::span<const StudyErrorField> study_error_fields();

/// The outcome of one run of a study (a row of study.csv).
struct StudyRunResult {
  const StudyRun* run = nullptr;
  std::string status;  ///< ok | invalid_mesh | failed
  int exit_code = 0;   ///< what `curvefem run` would return
  std::string message;
  nlohmann::json report;                           ///< report.json (null when the run failed)
  double meshing_s = 0, solve_s = 0, total_s = 0;  ///< NaN when unknown
  bool ok() const { return status == "ok"; }
  /// A number of the report; NaN when absent.
  double value(const char* key) const;
};

struct StudySettings {
  int threads = 0;  ///< as RunSettings::threads
};

struct StudyCallbacks {
  /// Before run `index` starts: the progress callback its run_case gets (may return empty).
  std::function<ProgressFn(int index, const StudyRun& run)> start;
  /// After run `index` (ok or not).
  std::function<void(int index, const StudyRunResult& row)> done;
};

struct StudyOutcome {
  nlohmann::ordered_json report;     ///< study.json as written
  std::vector<StudyRunResult> rows;  ///< one per run, in study order
  int failed = 0;                    ///< runs whose status is not ok
  std::string plot_problem;          ///< why study.png was not drawn ("" = drawn)
  int exit_code() const { return failed > 0 ? 3 : 0; }  ///< `curvefem study`'s
};

/// Runs the study and writes its outputs into study.output_dir. Throws IoError (and nothing is
/// left behind) when the outputs cannot be written; a failing run does not throw.
StudyOutcome run_study(const StudySpec& study, const StudySettings& settings = {},
                       const StudyCallbacks& callbacks = {});

}  // namespace curvefem::pipeline
