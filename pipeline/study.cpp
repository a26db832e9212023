// The study driver (study.hpp), shared by `curvefem study` and the Python module.
#include "pipeline/study.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <optional>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "pipeline/convergence_fit.hpp"
#include "pipeline/gnuplot_plot.hpp"
#include "pipeline/run_case.hpp"

namespace curvefem::pipeline {
namespace {

using json = nlohmann::json;
using ordered_json = nlohmann::ordered_json;  // study.json keeps its keys in a readable order
using RunRow = StudyRunResult;
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

constexpr StudyErrorField k_errors[] = {
    {"l2_error", "L2", true, 1, 7},
    {"h1_semi_error", "H1-semi", false, 0, 0},
    {"h1_error", "H1", true, 2, 5},
    {"surface_l2_error", "surface L2", true, 3, 9},
    {"surface_max_error", "surface max", false, 0, 0},
};
bool surface_error(const StudyErrorField& e) { return std::string(e.key).rfind("surface", 0) == 0; }

/// Runs with the same values of every sweep key but the refined one.
struct Series {
  std::string label;  ///< "degree=1 eps=0.01" ("" when the refined key is the only one)
  json parameters = json::object();
  std::vector<int> rows;  ///< sorted by DOFs
};

std::string format(const char* fmt, double v) {
  if (!std::isfinite(v)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

/// RFC 4180: quoted when it holds a comma, quote or line break.
std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

double stage_sum(const Timings& t, std::initializer_list<const char*> stages) {
  double s = 0;
  for (const char* stage : stages) s += t.get(stage);
  return s;
}

/// Curved meshes shared by several runs (issue 22: an ε study never rebuilds the shell): the
/// curved runs whose geometry and meshing differ at most in meshing.eps are meshed once, as the
/// ε levels of one coarsening (mesh_domain_levels); each run then solves on its level's Domain.
struct SharedMeshing {
  std::vector<std::shared_ptr<const Domain>> domain;  ///< per run (null: meshes alone)
  ordered_json report = ordered_json::array();        ///< study.json "shared_meshing"
};

SharedMeshing mesh_shared(const StudySpec& study, int threads) {
  SharedMeshing out;
  out.domain.resize(study.runs.size());
  std::map<std::string, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < study.runs.size(); ++i) {
    const CaseSpec& c = study.runs[i].spec;
    if (c.method != MeshingMethod::curved || !c.mesh_dir.empty() || !c.eps_levels.empty()) continue;
    json key = {{"geometry", c.resolved.value("geometry", json())},
                {"meshing", c.resolved.value("meshing", json())}};
    key["meshing"].erase("eps");
    groups[key.dump()].push_back(i);
  }
  for (const auto& [key, runs] : groups) {
    if (runs.size() < 2) continue;
    CaseSpec spec = study.runs[runs.front()].spec;
    std::vector<double> eps;
    for (std::size_t i : runs)
      if (std::find(eps.begin(), eps.end(), study.runs[i].spec.eps) == eps.end())
        eps.push_back(study.runs[i].spec.eps);
    spec.eps_levels = eps;
    Stopwatch watch;
    std::vector<Domain> domains;
    ordered_json entry;
    for (std::size_t i : runs) entry["runs"].push_back(study.runs[i].name);
    entry["eps"] = eps;
    try {
      log::info("study: meshing ", eps.size(), " eps level(s) once for ", runs.size(), " runs");
      nlohmann::json input_warnings;
      auto input_repair = std::make_shared<InputRepair>();
      domains = mesh_domain_levels(
          spec, load_surface(spec, {}, &input_warnings, input_repair.get()), {.threads = threads});
      for (Domain& d : domains) {
        d.report["input_warnings"] = input_warnings;
        if (input_repair->report.is_null()) continue;
        d.report["input_repair"] = input_repair->report;
        d.repair = input_repair;
      }
    } catch (const Error& e) {
      // Each run meshes alone and reports its own failure.
      log::warn("study: shared meshing failed (", e.what(), "); each run meshes alone");
      entry["failed"] = e.what();
      out.report.push_back(entry);
      continue;
    }
    entry["seconds"] = watch.seconds();
    out.report.push_back(entry);
    std::vector<std::shared_ptr<const Domain>> level(eps.size());
    for (std::size_t l = 0; l < eps.size(); ++l)
      level[l] = std::make_shared<const Domain>(std::move(domains[l]));
    for (std::size_t i : runs)
      out.domain[i] = level[std::size_t(std::find(eps.begin(), eps.end(), study.runs[i].spec.eps) -
                                        eps.begin())];
  }
  return out;
}

RunRow run_one(const StudySpec& study, const StudyRun& run, const std::filesystem::path& runs_dir,
               int threads, const ProgressFn& progress,
               std::shared_ptr<const Domain> domain = nullptr) {
  RunRow row;
  row.run = &run;
  CaseSpec spec = run.spec;
  spec.output_dir = runs_dir / run.name;  // staged; resolved_case.json names the final folder
  spec.resolved["output"]["dir"] = (study.output_dir / "runs" / run.name).string();
  Stopwatch watch;
  try {
    const RunOutcome outcome =
        run_case(spec, {.threads = threads, .domain = std::move(domain)}, progress);
    row.report = outcome.report;
    row.exit_code = outcome.exit_code;
    row.status = outcome.exit_code == 0 ? "ok" : "invalid_mesh";
    if (outcome.exit_code != 0)
      row.message = "the curved mesh failed its validation (meshing.validation in report.json)";
    row.meshing_s = stage_sum(outcome.timings, {"load_surface", "meshing", "load_mesh"});
    row.solve_s = stage_sum(outcome.timings, {"build_space", "assembly", "solve", "newton"});
    row.total_s = outcome.timings.get("total");
    return row;
  } catch (const Error& e) {
    row.exit_code = e.exit_code();
    row.message = e.what();
  } catch (const std::bad_alloc&) {
    row.exit_code = 3;
    row.message = "out of memory";
  } catch (const std::exception& e) {
    row.exit_code = 3;
    row.message = std::string("internal error: ") + e.what();
  }
  row.status = "failed";
  row.total_s = watch.seconds();
  return row;
}

std::vector<Series> group_series(const StudySpec& study, const std::vector<RunRow>& rows) {
  std::vector<Series> series;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    Series key;
    for (std::size_t i = 0; i < study.sweep.size(); ++i) {
      if (static_cast<int>(i) == study.refine) continue;
      const auto& v = rows[r].run->values[i];
      key.parameters[study.sweep[i].name] = v;
      key.label += (key.label.empty() ? "" : " ") + study.sweep[i].name + "=" + sweep_value_text(v);
    }
    auto it = std::find_if(series.begin(), series.end(),
                           [&](const Series& s) { return s.parameters == key.parameters; });
    if (it == series.end()) {
      series.push_back(key);
      it = series.end() - 1;
    }
    it->rows.push_back(static_cast<int>(r));
  }
  for (auto& s : series)
    std::stable_sort(s.rows.begin(), s.rows.end(), [&](int a, int b) {
      const double da = rows[a].value("dofs"), db = rows[b].value("dofs");
      return (std::isfinite(da) ? da : 0) < (std::isfinite(db) ? db : 0);
    });
  return series;
}

json optional_number(const std::optional<PowerLawFit>& f, double (*get)(const PowerLawFit&)) {
  return f ? json(get(*f)) : json(nullptr);
}

/// {"l2_error": {points, slope_dofs, rate_h, slope_tets, rate_h_tets, pairwise_rate_h}, ...}
json series_rates(const Series& s, const std::vector<RunRow>& rows) {
  json rates = json::object();
  for (const auto& e : k_errors) {
    std::vector<double> dofs, tets, err;
    for (int r : s.rows)
      if (rows[r].ok() && std::isfinite(rows[r].value(e.key))) {
        dofs.push_back(rows[r].value("dofs"));
        tets.push_back(rows[r].value("tets"));
        err.push_back(rows[r].value(e.key));
      }
    if (err.empty()) continue;
    const auto by_dofs = fit_power_law(dofs, err);
    const auto by_tets = fit_power_law(tets, err);
    json j;
    j["points"] = err.size();
    j["slope_dofs"] = optional_number(by_dofs, [](const PowerLawFit& f) { return f.slope; });
    j["rate_h"] = optional_number(by_dofs, [](const PowerLawFit& f) { return f.rate_h(); });
    j["slope_tets"] = optional_number(by_tets, [](const PowerLawFit& f) { return f.slope; });
    j["rate_h_tets"] = optional_number(by_tets, [](const PowerLawFit& f) { return f.rate_h(); });
    j["pairwise_rate_h"] = pairwise_rates_h(dofs, err);
    rates[e.key] = j;
  }
  return rates;
}

std::string study_csv(const StudySpec& study, const std::vector<RunRow>& rows, bool surface) {
  std::vector<std::string> header = {"name"};
  for (const auto& k : study.sweep) header.push_back(k.name);
  auto swept = [&](const std::string& name) {
    return std::any_of(study.sweep.begin(), study.sweep.end(),
                       [&](const SweepKey& k) { return k.name == name; });
  };
  header.insert(header.end(), {"status", "exit_code", "dofs", "tets"});
  const bool order_column = !swept("order"), degree_column = !swept("degree");
  if (order_column) header.push_back("order");
  if (degree_column) header.push_back("degree");
  for (const auto& e : k_errors)
    if (surface || !surface_error(e)) header.push_back(e.key);
  header.insert(header.end(), {"meshing_s", "solve_s", "total_s", "message"});

  std::string text;
  auto line = [&](const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) text += (i ? "," : "") + csv_cell(cells[i]);
    text += "\n";
  };
  line(header);
  for (const auto& row : rows) {
    std::vector<std::string> cells = {row.run->name};
    for (const auto& v : row.run->values) cells.push_back(sweep_value_text(v));
    cells.push_back(row.status);
    cells.push_back(std::to_string(row.exit_code));
    for (const char* key : {"dofs", "tets"}) cells.push_back(format("%.0f", row.value(key)));
    if (order_column) cells.push_back(format("%.0f", row.value("order")));
    if (degree_column) cells.push_back(format("%.0f", row.value("degree")));
    for (const auto& e : k_errors)
      if (surface || !surface_error(e)) cells.push_back(format("%.9g", row.value(e.key)));
    cells.push_back(format("%.4f", row.meshing_s));
    cells.push_back(format("%.4f", row.solve_s));
    cells.push_back(format("%.4f", row.total_s));
    cells.push_back(row.message);
    line(cells);
  }
  return text;
}

LogLogPlot study_plot(const StudySpec& study, const std::vector<RunRow>& rows,
                      const std::vector<Series>& series, const std::vector<json>& rates) {
  LogLogPlot plot;
  const bool by_tets = study.x == "tets";
  plot.output = "study.png";
  plot.title = study.file.stem().string() + ": error vs " + (by_tets ? "tets" : "DOFs") +
               " along " + study.sweep[study.refine].name + "; rate = fitted order in h ~ " +
               (by_tets ? "tets" : "DOFs") + "^(-1/3)";
  plot.xlabel = by_tets ? "tetrahedra" : "degrees of freedom";
  plot.ylabel = "error";
  for (std::size_t s = 0; s < series.size(); ++s)
    for (const auto& e : k_errors) {
      if (!e.plotted || !rates[s].contains(e.key)) continue;
      PlotCurve curve;
      curve.color = static_cast<int>(s) + 1;
      curve.dash = e.dash;
      curve.point_type = e.point;
      for (int r : series[s].rows)
        if (rows[r].ok() && std::isfinite(rows[r].value(e.key))) {
          curve.x.push_back(rows[r].value(by_tets ? "tets" : "dofs"));
          curve.y.push_back(rows[r].value(e.key));
        }
      curve.title = series[s].label + (series[s].label.empty() ? "" : "  ") + e.label;
      const json& rate = rates[s][e.key][by_tets ? "rate_h_tets" : "rate_h"];
      if (rate.is_number()) curve.title += "  rate " + format("%.2f", rate.get<double>());
      plot.curves.push_back(std::move(curve));
    }
  return plot;
}

/// Replaces `dir`/runs by `staged_runs` (the runs of this study only).
void move_runs_into_place(const std::filesystem::path& staged_runs,
                          const std::filesystem::path& dir) {
  const auto target = dir / "runs";
  const auto old = dir / (".old-runs-" + std::to_string(getpid()));
  std::error_code ec;
  std::filesystem::remove_all(old, ec);
  if (std::filesystem::exists(target)) {
    std::filesystem::rename(target, old, ec);
    if (ec)
      throw IoError("cannot move the previous runs aside: " + ec.message(),
                    {.file = target.string()});
  }
  std::filesystem::rename(staged_runs, target, ec);
  if (ec) throw IoError("cannot move runs into place: " + ec.message(), {.file = target.string()});
  std::filesystem::remove_all(old, ec);
}

}  // namespace

std::span<const StudyErrorField> study_error_fields() { return k_errors; }

double StudyRunResult::value(const char* key) const {
  return report.is_object() && report.contains(key) && report[key].is_number()
             ? report[key].get<double>()
             : k_nan;
}

StudyOutcome run_study(const StudySpec& study, const StudySettings& settings,
                       const StudyCallbacks& callbacks) {
  Stopwatch total;
  StudyOutcome outcome;
  const bool existed = std::filesystem::exists(study.output_dir);
  std::optional<StagedOutputDir> staged;
  std::vector<RunRow> rows;
  std::vector<Series> series;
  std::vector<json> rates;
  std::string plot_problem;
  SharedMeshing shared;
  try {
    staged.emplace(study.output_dir);
    const auto runs_dir = staged->path("runs");
    std::filesystem::create_directory(runs_dir);
    shared = mesh_shared(study, settings.threads);
    for (std::size_t i = 0; i < study.runs.size(); ++i) {
      const int index = static_cast<int>(i);
      const ProgressFn run_progress =
          callbacks.start ? callbacks.start(index, study.runs[i]) : ProgressFn();
      rows.push_back(run_one(study, study.runs[i], runs_dir, settings.threads, run_progress,
                             shared.domain[i]));
      if (callbacks.done) callbacks.done(index, rows.back());
    }
    series = group_series(study, rows);
    for (const auto& s : series) rates.push_back(series_rates(s, rows));
    const bool surface = std::any_of(study.runs.begin(), study.runs.end(),
                                     [](const StudyRun& r) { return r.spec.dense_surface(); });

    write_text_file_atomic(staged->path("study.csv"), study_csv(study, rows, surface));
    write_text_file_atomic(staged->path("study.gp"),
                           gnuplot_script(study_plot(study, rows, series, rates)));
    plot_problem = run_gnuplot(staged->path(""), "study.gp");
    if (!plot_problem.empty()) {
      std::error_code ec;
      std::filesystem::remove(staged->path("study.png"), ec);
      std::filesystem::remove(staged->final_path("study.png"), ec);  // not a stale one
      log::warn("study.png not written: ", plot_problem);
    }

    ordered_json& report = outcome.report;
    report["command"] = "study";
    report["study"] = study.resolved;
    report["runs"] = ordered_json::array();
    int failed = 0;
    for (const auto& row : rows) {
      ordered_json r;
      r["name"] = row.run->name;
      r["parameters"] = ordered_json::object();
      for (std::size_t i = 0; i < study.sweep.size(); ++i)
        r["parameters"][study.sweep[i].name] = row.run->values[i];
      r["status"] = row.status;
      r["exit_code"] = row.exit_code;
      if (!row.message.empty()) r["message"] = row.message;
      if (row.status != "failed") {
        r["dir"] = "runs/" + row.run->name;
        for (const char* key : {"dofs", "tets", "order", "degree"}) r[key] = row.report[key];
        for (const auto& e : k_errors)
          if (row.report.contains(e.key)) r[e.key] = row.report[e.key];
      }
      r["meshing_s"] =
          std::isfinite(row.meshing_s) ? ordered_json(row.meshing_s) : ordered_json(nullptr);
      r["solve_s"] = std::isfinite(row.solve_s) ? ordered_json(row.solve_s) : ordered_json(nullptr);
      r["total_s"] = row.total_s;
      failed += !row.ok();
      report["runs"].push_back(r);
    }
    report["series"] = ordered_json::array();
    for (std::size_t s = 0; s < series.size(); ++s) {
      ordered_json entry;
      entry["label"] = series[s].label;
      entry["parameters"] = series[s].parameters;
      entry["along"] = study.sweep[study.refine].name;
      entry["runs"] = ordered_json::array();
      for (int r : series[s].rows) entry["runs"].push_back(rows[r].run->name);
      entry["rates"] = rates[s];
      report["series"].push_back(entry);
    }
    report["rate_definition"] =
        "least-squares slope of log(error) vs log(DOFs) (slope_dofs) or log(tets) (slope_tets) "
        "over the ok runs of a series; rate_h = -3 * slope_dofs (h ~ DOFs^(-1/3)), rate_h_tets = "
        "-3 * slope_tets";
    report["failed_runs"] = failed;
    // Runs that solved on a shared mesh have no meshing time of their own (meshing_s 0).
    report["shared_meshing"] = shared.report;
    report["plot"] = plot_problem.empty() ? ordered_json("study.png") : ordered_json(nullptr);
    if (!plot_problem.empty()) report["plot_problem"] = plot_problem;
    report["threads"] = settings.threads;
    report["time_s"] = total.seconds();

    move_runs_into_place(runs_dir, study.output_dir);
    staged->commit();
    staged.reset();
    write_text_file_atomic(study.output_dir / "study.json", report.dump(2) + "\n");
  } catch (...) {
    staged.reset();  // removes the staging folder and the runs in it
    std::error_code ec;
    if (!existed) std::filesystem::remove(study.output_dir, ec);  // only if empty
    throw;
  }

  outcome.failed = static_cast<int>(
      std::count_if(rows.begin(), rows.end(), [](const RunRow& r) { return !r.ok(); }));
  outcome.rows = std::move(rows);
  outcome.plot_problem = plot_problem;
  return outcome;
}

}  // namespace curvefem::pipeline
