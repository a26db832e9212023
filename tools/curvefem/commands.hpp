// Subcommand registry of the curvefem CLI. Each cmd_*.cpp defines one register_* function that
// adds its CLI11 subcommand and the closure that runs it.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace curvefem::cli {

/// Records `run` as the action of subcommand `sub`.
void add_command(CLI::App* sub, std::function<int()> run);

void register_check(CLI::App& app);     // cmd_check.cpp
void register_convert(CLI::App& app);   // cmd_convert.cpp
void register_demo(CLI::App& app);      // cmd_demo.cpp
void register_generate(CLI::App& app);  // cmd_generate.cpp
void register_run(CLI::App& app);       // cmd_run.cpp
void register_remesh(CLI::App& app);    // cmd_remesh.cpp
void register_shell(CLI::App& app);     // cmd_shell.cpp
void register_mesh(CLI::App& app);      // cmd_mesh.cpp
void register_validate(CLI::App& app);  // cmd_validate.cpp
void register_study(CLI::App& app);     // cmd_study.cpp
void register_schema(CLI::App& app);    // cmd_schema.cpp
void register_param(CLI::App& app);     // cmd_param.cpp
void register_deform(CLI::App& app);    // cmd_deform.cpp

inline void register_commands(CLI::App& app) {
  register_check(app);
  register_convert(app);
  register_demo(app);
  register_generate(app);
  register_run(app);
  register_remesh(app);
  register_shell(app);
  register_mesh(app);
  register_validate(app);
  register_study(app);
  register_schema(app);
  register_param(app);
  register_deform(app);
}

/// Runs the action of the parsed subcommand and returns its exit code.
int run_selected(CLI::App& app);

}  // namespace curvefem::cli
