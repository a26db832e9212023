#include "tools/curvefem/commands.hpp"

#include <utility>
#include <vector>

#include "tools/curvefem/cli_common.hpp"

namespace curvefem::cli {
namespace {
std::vector<std::pair<CLI::App*, std::function<int()>>>& registry() {
  static std::vector<std::pair<CLI::App*, std::function<int()>>> commands;
  return commands;
}
}  // namespace

void add_command(CLI::App* sub, std::function<int()> run) {
  registry().emplace_back(sub, std::move(run));
}

int run_selected(CLI::App& app) {
  for (auto& [sub, run] : registry())
    if (sub->parsed()) return guarded(run);
  return 1;
}

}  // namespace curvefem::cli
