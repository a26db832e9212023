// `curvefem study STUDY.json [-o DIR]`: a convergence study (pipeline/study.hpp runs it; format in
// cases/README.md, "Studies"). This file parses the command line, shows the progress and prints
// the fitted rates. A bad study file exits 2 before anything is created; a run that fails is a
// row with its status and message, the others go on, and the study exits 3.
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/progress.hpp"
#include "meshing/core/timer.hpp"
#include "pipeline/study.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {
namespace {

using json = nlohmann::json;
using pipeline::study_error_fields;
using pipeline::StudyRunResult;

struct StudyOptions {
  GlobalOptions global;
  std::string study_file;
  std::string output;
  bool log_level_given = false;
};

std::string format(const char* fmt, double v) {
  if (!std::isfinite(v)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

/// Shows one line per finished run; on a terminal also the stage of the run in progress (the
/// run's own progress bar, prefixed with the run, its finished stages erased).
class StudyProgress {
 public:
  StudyProgress(ProgressMode mode, int total)
      : m_mode(mode),
        m_total(total),
        m_run(mode == ProgressMode::bar ? ProgressMode::bar : ProgressMode::quiet) {
    m_run.set_transient(true);
  }
  TerminalProgress& start(int i, const std::string& name) {
    if (m_mode == ProgressMode::bar) {
      m_run.set_prefix("[" + std::to_string(i + 1) + "/" + std::to_string(m_total) + "] " + name +
                       "  ");
      std::fprintf(stderr, "\r\033[K[%d/%d] %s  starting", i + 1, m_total, name.c_str());
      std::fflush(stderr);
    }
    return m_run;
  }
  void done(int i, const StudyRunResult& row) {
    m_run.end_stage();
    if (m_mode == ProgressMode::quiet) return;
    if (m_mode == ProgressMode::bar) std::fprintf(stderr, "\r\033[K");
    std::string what;
    if (row.status == "failed") {
      what = "FAILED (exit " + std::to_string(row.exit_code) + "): " + row.message;
    } else {
      what = row.status + "  " + std::to_string(row.report.value("dofs", 0LL)) + " dofs";
      for (const auto& e : study_error_fields())
        if (e.plotted && std::isfinite(row.value(e.key)))
          what += std::string("  ") + e.label + " " + format("%.3e", row.value(e.key));
    }
    std::fprintf(stderr, "[%d/%d] %s  %s  (%.2f s)\n", i + 1, m_total, row.run->name.c_str(),
                 what.c_str(), row.total_s);
    std::fflush(stderr);
  }

 private:
  ProgressMode m_mode;
  int m_total;
  TerminalProgress m_run;  ///< handed to each run
};

int run_study(const StudyOptions& o) {
  apply_global_options(o.global);
  // The runs' own info lines would drown the study's progress: warnings only, unless asked.
  if (!o.global.quiet && !o.log_level_given) log::set_level(log::Level::warn);
  const ProgressMode mode = TerminalProgress::automatic_mode(o.global.quiet);
  Stopwatch total;
  // exit 2 here creates nothing
  const pipeline::StudySpec study = pipeline::read_study(o.study_file, o.output);
  StudyProgress progress(mode, static_cast<int>(study.runs.size()));
  const pipeline::StudyOutcome outcome = pipeline::run_study(
      study, {.threads = o.global.threads},
      {.start =
           [&](int i, const pipeline::StudyRun& run) {
             return progress.start(i, run.name).callback();
           },
       .done = [&](int i, const StudyRunResult& row) { progress.done(i, row); }});

  if (!o.global.quiet) {
    std::printf("curvefem study: %zu runs, %d failed, in %.1f s\n", outcome.rows.size(),
                outcome.failed, total.seconds());
    for (const auto& series : outcome.report["series"]) {
      const std::string label = series["label"].get<std::string>();
      for (const auto& e : study_error_fields()) {
        if (!e.plotted || !series["rates"].contains(e.key)) continue;
        const auto& r = series["rates"][e.key];
        auto rate = [](const nlohmann::ordered_json& v) {
          return v.is_number() ? format("%5.2f", v.get<double>()) : std::string("  -  ");
        };
        std::printf("  %-24s %-10s rate in h: %s (from DOFs)  %s (from tets)  over %d runs\n",
                    label.empty() ? "(all)" : label.c_str(), e.label, rate(r["rate_h"]).c_str(),
                    rate(r["rate_h_tets"]).c_str(), r["points"].get<int>());
      }
    }
    std::printf("  results in %s (study.csv, study.json%s, runs/)\n", study.output_dir.c_str(),
                outcome.plot_problem.empty() ? ", study.png" : "");
  }
  if (outcome.failed > 0)
    std::fprintf(stderr,
                 "curvefem study: %d of %zu runs failed (status and message in study.csv)\n",
                 outcome.failed, outcome.rows.size());
  return outcome.exit_code();
}

}  // namespace

void register_study(CLI::App& app) {
  auto options = std::make_shared<StudyOptions>();
  CLI::App* sub = app.add_subcommand(
      "study", "convergence study: sweep degree, order, eps or a refinement level over a case");
  sub->add_option("study", options->study_file, "study file (format: cases/README.md, Studies)")
      ->required();
  sub->add_option("-o,--output", options->output, "output directory (overrides output.dir)");
  add_global_options(*sub, options->global);
  CLI::Option* level = sub->get_option("--log-level");
  add_command(sub, [options, level] {
    options->log_level_given = level->count() > 0;
    return run_study(*options);
  });
}

}  // namespace curvefem::cli
