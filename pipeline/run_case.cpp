#include "pipeline/run_case.hpp"

#include <algorithm>

#include "pipeline/report_json.hpp"
#include "pipeline/stages.hpp"

namespace curvefem::pipeline {

RunOutcome run_case(const CaseSpec& spec, const RunSettings& settings, const ProgressFn& progress) {
  Stopwatch total;
  RunOutcome outcome;
  const StageContext ctx{
      .threads = settings.threads, .progress = progress, .timings = &outcome.timings};
  auto r = std::make_shared<RunResults>();
  SurfaceMesh input;
  if (spec.dense_surface()) input = load_surface(spec, ctx);
  r->domain = mesh_domain(spec, std::move(input), ctx);
  // Adaptive p (CaseSpec::target_error): the same mesh, degree raised until the estimate meets
  // the target or p = 4; the outputs and report are those of the last degree.
  CaseSpec run = spec;
  const std::vector<LoadCase> loads = spec.loads();
  std::shared_ptr<fem::FactorizationCache> cache;
  nlohmann::json iterations = nlohmann::json::array();
  double estimate = 0;
  for (;;) {
    Stopwatch step;
    r->disc = discretize(run, r->domain, ctx);
    // Load cases with the same Dirichlet part share the matrix: one factorization for them.
    cache = loads.size() > 1 ? std::make_shared<fem::FactorizationCache>() : nullptr;
    r->loads.clear();
    for (const LoadCase& load : loads)
      r->loads.push_back(solve_load(run, load, r->domain, r->disc, ctx, cache));
    if (!(spec.target_error > 0)) break;
    estimate = 0;
    for (const LoadResult& l : r->loads)
      estimate = std::max(estimate, l.errors.report["error_estimate"]["relative"].get<double>());
    iterations.push_back({{"degree", run.degree},
                          {"dofs", r->disc.space.num_dofs},
                          {"estimate_relative", estimate},
                          {"seconds", step.seconds()}});
    if (estimate <= spec.target_error || run.degree >= 4) break;
    ++run.degree;
  }
  outcome.report = run_report(run, r->domain, r->disc, r->loads);
  if (spec.target_error > 0)
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
  }
  outcome.report["threads"] = settings.threads;
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
