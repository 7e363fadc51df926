// The subcommands of `keel-worker`. Adding one: a file `<name>_command.cc` defining
// `add_<name>_command`, its declaration here, and a line in main.cc's list.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace keel::worker {

// A subcommand registered on the app; `main` runs it once the command line is parsed and
// returns the process exit code.
struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> main;
};

// Exit codes shared by the subcommands.
inline constexpr int kExitOk = 0;
inline constexpr int kExitUsage = 1;
inline constexpr int kExitStageFailed = 2;
inline constexpr int kExitInterrupted = 130;

Subcommand add_serve_command(CLI::App& app);  // serve_command.cc (the default)
Subcommand add_run_command(CLI::App& app);    // run_command.cc
Subcommand add_ate_command(CLI::App& app);    // ate_command.cc (evo_ape)
Subcommand add_rpe_command(CLI::App& app);    // rpe_command.cc (evo_rpe)
Subcommand add_filter_command(CLI::App& app);   // filter_command.cc (map filter chains)
Subcommand add_metrics_command(CLI::App& app);  // metrics_command.cc (Table V metrics)
Subcommand add_compare_command(CLI::App& app);  // compare_command.cc (two job folders)
Subcommand add_options_command(CLI::App& app);  // options_command.cc (stage options, docs)
Subcommand add_init_command(CLI::App& app);     // init_command.cc (mission.yaml from a bag)

}  // namespace keel::worker
