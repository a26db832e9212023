#include "pipeline/run_case.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "fem/solvers/distributed.hpp"
#include "meshing/core/error.hpp"
#include "pipeline/report_json.hpp"
#include "pipeline/stages.hpp"

namespace curvefem::pipeline {

namespace {

// The solves on one Domain (r.domain): every load case at run.degree, and with adaptive p
// (CaseSpec::target_error) the degree raised until the estimate meets the target or p = 4.
// Returns the largest relative estimate over the load cases; `iterations` gets a row per degree.
double solve_adaptive_p(const CaseSpec& spec, CaseSpec& run, RunResults& r,
                        const std::vector<LoadCase>& loads, const StageContext& ctx,
                        std::shared_ptr<fem::FactorizationCache>& cache,
                        nlohmann::json& iterations) {
  double estimate = 0;
  for (;;) {
    Stopwatch step;
    r.disc = discretize(run, r.domain, ctx);
    // Load cases with the same Dirichlet part share the matrix: one factorization for them.
    cache = loads.size() > 1 ? std::make_shared<fem::FactorizationCache>() : nullptr;
    r.loads.clear();
    for (const LoadCase& load : loads)
      r.loads.push_back(solve_load(run, load, r.domain, r.disc, ctx, cache));
    estimate = 0;
    for (const LoadResult& l : r.loads)
      estimate = std::max(estimate, l.errors.report["error_estimate"]["relative"].get<double>());
    if (!(spec.target_error > 0)) break;
    iterations.push_back({{"degree", run.degree},
                          {"dofs", r.disc.space.num_dofs},
                          {"estimate_relative", estimate},
                          {"seconds", step.seconds()}});
    if (estimate <= spec.target_error || run.degree >= 4) break;
    ++run.degree;
  }
  return estimate;
}

// What a level's solution is compared by: u_h on every input vertex and ||grad u_h||, per load.
struct LevelValues {
  std::vector<Eigen::MatrixXd> on_input;
  std::vector<double> gradient_norm;
};

LevelValues level_values(const RunResults& r) {
  LevelValues v;
  for (const LoadResult& l : r.loads) {
    v.on_input.push_back(l.on_input ? l.on_input->values : Eigen::MatrixXd());
    v.gradient_norm.push_back(l.errors.report["error_estimate"]["gradient_norm"].get<double>());
  }
  return v;
}

}  // namespace

RunOutcome run_case(const CaseSpec& spec, const RunSettings& settings, const ProgressFn& progress) {
  Stopwatch total;
  RunOutcome outcome;
  const StageContext ctx{
      .threads = settings.threads, .progress = progress, .timings = &outcome.timings};
  auto r = std::make_shared<RunResults>();
  SurfaceMesh input;
  nlohmann::json input_warnings;  // curvefem check's, in the meshing section (as mesh's report)
  auto input_repair = std::make_shared<InputRepair>();  // meshing.merge_short_edges
  if (spec.dense_surface() && !settings.domain)
    input = load_surface(spec, ctx, &input_warnings, input_repair.get());
  auto note_repair = [&](Domain& d, double eps) {
    if (input_repair->report.is_null()) return;
    d.report["input_repair"] = input_repair->report;
    if (d.curved_map)
      d.report["input_repair"]["original_distance"] = original_distance_json(
          input_repair->original.V, input_repair->vertex_map, *d.curved_map, eps);
    d.repair = input_repair;
  };
  CaseSpec run = spec;
  const std::vector<LoadCase> loads = spec.loads();
  std::shared_ptr<fem::FactorizationCache> cache;
  nlohmann::json iterations = nlohmann::json::array();
  double estimate = 0;
  nlohmann::json levels_report;
  if (settings.domain && !spec.eps_levels.empty())
    throw InputError("run: a given Domain and meshing.eps a list");
  if (settings.domain) {
    r->domain = *settings.domain;
    estimate = solve_adaptive_p(spec, run, *r, loads, ctx, cache, iterations);
  } else if (spec.eps_levels.empty()) {
    r->domain = mesh_domain(spec, std::move(input), ctx);
    if (!input_warnings.is_null()) r->domain.report["input_warnings"] = input_warnings;
    note_repair(r->domain, spec.eps);
    // Adaptive p (CaseSpec::target_error): the same mesh, degree raised until the estimate meets
    // the target or p = 4; the outputs and report are those of the last degree.
    estimate = solve_adaptive_p(spec, run, *r, loads, ctx, cache, iterations);
  } else {
    // ε levels (meshing.eps a list): every level meshed from one coarsening, then solved coarse
    // to fine. Level i is compared with level i-1 on what both define: u_h on the dense input's
    // vertices (through each level's φ) and ||grad u_h||; with target_error the run stops at the
    // first level whose change from the coarser one and whose own estimate are both within it
    // (the change estimates the coarser level's error, so the level kept is expected to be
    // better). The outputs and report are those of the last level solved.
    std::vector<Domain> domains = mesh_domain_levels(spec, std::move(input), ctx);
    for (std::size_t i = 0; i < domains.size(); ++i) {
      Domain& d = domains[i];
      if (!input_warnings.is_null()) d.report["input_warnings"] = input_warnings;
      note_repair(d, spec.eps_levels[i]);
    }
    nlohmann::json rows = nlohmann::json::array();
    std::optional<LevelValues> previous;
    bool reached = false;
    for (std::size_t i = 0; i < domains.size(); ++i) {
      Stopwatch step;
      r->domain = std::move(domains[i]);
      run.eps = spec.eps_levels[i];
      nlohmann::json p_iterations = nlohmann::json::array();
      estimate = solve_adaptive_p(spec, run, *r, loads, ctx, cache, p_iterations);
      const LevelValues now = level_values(*r);
      double change_rms = -1, change_max = -1, change_gradient = -1;
      bool compared = true;  // every load case's values on the input compared
      if (previous) {
        change_rms = change_max = change_gradient = 0;
        for (std::size_t l = 0; l < loads.size(); ++l) {
          const Eigen::MatrixXd &a = now.on_input[l], &b = previous->on_input[l];
          compared = compared && a.size() > 0 && a.rows() == b.rows() && a.cols() == b.cols();
          if (a.size() > 0 && a.rows() == b.rows() && a.cols() == b.cols()) {
            const double scale_rms = std::sqrt(a.squaredNorm() / double(a.rows()));
            const double scale_max = a.cwiseAbs().maxCoeff();
            const Eigen::MatrixXd d = a - b;
            if (scale_rms > 0)
              change_rms =
                  std::max(change_rms, std::sqrt(d.squaredNorm() / double(d.rows())) / scale_rms);
            if (scale_max > 0)
              change_max = std::max(change_max, d.cwiseAbs().maxCoeff() / scale_max);
          }
          if (now.gradient_norm[l] > 0)
            change_gradient = std::max(
                change_gradient,
                std::abs(now.gradient_norm[l] - previous->gradient_norm[l]) / now.gradient_norm[l]);
        }
      }
      nlohmann::json row = {
          {"eps", run.eps},
          {"coarse_faces", r->domain.report.value("coarse_faces", 0)},
          {"tets", r->domain.mesh.num_cells()},
          {"valid", r->domain.valid},
          {"degree", run.degree},
          {"dofs", r->disc.space.num_dofs},
          {"estimate_relative", estimate},
          {"change_on_input_rms_rel", previous ? nlohmann::json(change_rms) : nlohmann::json()},
          {"change_on_input_max_rel", previous ? nlohmann::json(change_max) : nlohmann::json()},
          {"change_gradient_norm_rel",
           previous ? nlohmann::json(change_gradient) : nlohmann::json()},
          {"solve_seconds", step.seconds()}};
      if (spec.target_error > 0) row["degrees"] = p_iterations;
      double l2 = -1;
      for (const LoadResult& l : r->loads)
        if (l.errors.report.contains("l2_error") && l.errors.report["l2_norm_exact"] > 0)
          l2 = std::max(l2, l.errors.report["l2_error"].get<double>() /
                                l.errors.report["l2_norm_exact"].get<double>());
      if (l2 >= 0) row["l2_error_relative"] = l2;
      rows.push_back(row);
      const double change = std::max(change_rms, change_gradient);
      reached = spec.target_error > 0 && previous && compared && change <= spec.target_error &&
                estimate <= spec.target_error;
      previous = now;
      if (reached) break;
    }
    levels_report = {
        {"method",
         "meshes for every eps from one shell and one coarsening (build_curved_mesh_levels), "
         "solved coarse to fine; change_* compare a level with the coarser one: u_h on the dense "
         "input's vertices (RMS and max, relative to this level's) and ||grad u_h|| (relative); "
         "with target_error the run stops at the first level where the larger of the RMS and "
         "gradient changes and the gradient-recovery estimate are within it"},
        {"levels", rows},
        {"eps", run.eps}};
    if (spec.target_error > 0) {
      levels_report["target_error"] = spec.target_error;
      levels_report["reached"] = reached;
      levels_report["reason"] = reached ? "the change from the coarser level and the estimate "
                                          "meet the target"
                                        : "the finest level reached above the target";
    }
  }
  outcome.report = run_report(run, r->domain, r->disc, r->loads);
  if (!levels_report.is_null()) outcome.report["eps_levels"] = levels_report;
  if (spec.target_error > 0 && spec.eps_levels.empty())
    outcome.report["adaptive"] = {
        {"method",
         "p: the degree raised on the same mesh until the gradient-recovery estimate "
         "eta / |grad u_h| of every load case is at most target_error"},
        {"target_error", spec.target_error},
        {"iterations", iterations},
        {"reached", estimate <= spec.target_error},
        {"reason", estimate <= spec.target_error ? "the estimate meets the target"
                                                 : "p = 4 reached above the target"}};
  if (cache) {
    outcome.report["factorizations"] = cache->factorizations();
    outcome.report["factorization_reuses"] = cache->reuses();
    outcome.report["stiffness_assemblies"] = cache->assemblies();
    outcome.report["stiffness_reuses"] = cache->assembly_reuses();
  }
  outcome.report["threads"] = settings.threads;
  outcome.report["ranks"] = fem::distributed::size();
  if (settings.write) {
    write_outputs(run, r->domain, r->disc, r->loads,
                  {.paraview = settings.paraview, .total = &total}, outcome.report, ctx);
  } else {
    outcome.timings.add("total", total.seconds());
    outcome.report["time_s"] = timings_json(outcome.timings);
  }
  outcome.exit_code = r->domain.valid ? 0 : 3;
  outcome.results = std::move(r);
  return outcome;
}

}  // namespace curvefem::pipeline
