#include "pipeline/run_case.hpp"

#include "pipeline/stages.hpp"

namespace curvefem::pipeline {

RunOutcome run_case(const CaseSpec& spec, const RunSettings& settings, const ProgressFn& progress) {
  Stopwatch total;
  RunOutcome outcome;
  const StageContext ctx{
      .threads = settings.threads, .progress = progress, .timings = &outcome.timings};
  SurfaceMesh input;
  if (spec.dense_surface()) input = load_surface(spec, ctx);
  const Domain domain = mesh_domain(spec, std::move(input), ctx);
  const Discretization disc = discretize(spec, domain, ctx);
  const BoundaryData data = bind_boundary(spec, spec.boundary_conditions, domain, disc);
  const Solution solution = solve(spec, disc, data, spec.rhs, ctx);
  const ErrorResult errors = compute_errors(spec, disc, solution, ctx);
  std::optional<InputSolution> on_input;
  if (domain.on_input()) on_input = transfer_to_input(spec, domain, disc, solution, errors, ctx);
  outcome.report =
      run_report(spec, domain, disc, solution, errors, on_input ? &*on_input : nullptr);
  outcome.report["threads"] = settings.threads;
  write_outputs(spec, domain, disc, solution, errors, on_input ? &*on_input : nullptr,
                {.paraview = settings.paraview, .total = &total}, outcome.report, ctx);
  outcome.exit_code = domain.valid ? 0 : 3;
  return outcome;
}

}  // namespace curvefem::pipeline
