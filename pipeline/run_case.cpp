#include "pipeline/run_case.hpp"

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
  r->disc = discretize(spec, r->domain, ctx);
  // Load cases with the same Dirichlet part share the matrix: one factorization for them.
  const std::vector<LoadCase> loads = spec.loads();
  auto cache = loads.size() > 1 ? std::make_shared<fem::FactorizationCache>() : nullptr;
  for (const LoadCase& load : loads)
    r->loads.push_back(solve_load(spec, load, r->domain, r->disc, ctx, cache));
  outcome.report = run_report(spec, r->domain, r->disc, r->loads);
  if (cache) {
    outcome.report["factorizations"] = cache->factorizations();
    outcome.report["factorization_reuses"] = cache->reuses();
  }
  outcome.report["threads"] = settings.threads;
  if (settings.write) {
    write_outputs(spec, r->domain, r->disc, r->loads,
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
