// `curvefem run CASE.json [-o DIR] [--paraview]`: the whole pipeline of DESIGN.md §1, as composed
// by pipeline::run_case (pipeline/run_case.hpp; its stages: pipeline/stages.hpp). This file only
// parses the command line and prints the summary.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "pipeline/case_file.hpp"
#include "pipeline/run_case.hpp"
#include "tools/curvefem/cli_common.hpp"
#include "tools/curvefem/commands.hpp"

namespace curvefem::cli {
namespace {

using json = nlohmann::json;

struct RunOptions {
  GlobalOptions global;
  std::string case_file;
  std::string output;
  bool paraview = false;
};

int run_command(const RunOptions& o) {
  auto progress = apply_global_options(o.global);
  const pipeline::CaseSpec spec = pipeline::read_case(o.case_file, o.output);
  const pipeline::RunOutcome outcome = pipeline::run_case(
      spec, {.threads = o.global.threads, .paraview = o.paraview}, progress->callback());
  progress->end_stage();
  const json& report = outcome.report;
  if (!o.global.quiet) {
    std::printf("curvefem run: %s (%s), degree %d on %d tets of order %d: %lld unknowns\n",
                pipeline::to_string(spec.physics).c_str(), pipeline::to_string(spec.method).c_str(),
                spec.degree, report["tets"].get<int>(), report["order"].get<int>(),
                report["dofs"].get<long long>());
    auto errors = [](const json& r, const char* indent) {
      if (r.contains("l2_error"))
        std::printf("%sL2 error %.3e   H1-semi error %.3e\n", indent, r["l2_error"].get<double>(),
                    r["h1_semi_error"].get<double>());
      if (r.contains("surface_l2_error"))
        std::printf("%son the input surface (%d vertices): L2 error %.3e   max error %.3e\n",
                    indent, r["surface_vertices"].get<int>(), r["surface_l2_error"].get<double>(),
                    r["surface_max_error"].get<double>());
    };
    if (report.contains("load_cases")) {
      for (const json& l : report["load_cases"]) {
        std::printf(
            "  load case %s: solver %s, %d iterations\n", l["name"].get<std::string>().c_str(),
            l["solver"]["method"].get<std::string>().c_str(), l["solver"]["iterations"].get<int>());
        errors(l, "    ");
      }
    } else {
      errors(report, "  ");
    }
    for (const auto& [stage, sec] : outcome.timings.stages())
      std::printf("  %-16s %8.3f s\n", stage.c_str(), sec);
    std::printf("  results in %s\n", spec.output_dir.c_str());
  }
  if (outcome.exit_code == 3)
    std::fprintf(stderr,
                 "curvefem run: the curved mesh failed its validation (see meshing.validation "
                 "in report.json)\n");
  return outcome.exit_code;
}

}  // namespace

void register_run(CLI::App& app) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* sub = app.add_subcommand("run", "solve the case described by a JSON case file");
  sub->add_option("case", options->case_file, "case file (schema: cases/README.md)")->required();
  sub->add_option("-o,--output", options->output, "output directory (overrides output.dir)");
  sub->add_flag("--paraview", options->paraview,
                "also write open_in_paraview.py (a ParaView Python state script)");
  add_global_options(*sub, options->global);
  add_command(sub, [options] { return run_command(*options); });
}

}  // namespace curvefem::cli
