// keel-worker: leases jobs from a Keel server and runs their stages (`serve`, the default),
// or runs stages locally on a mission folder (`run`).
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <string>
#include <vector>

#include "worker/main/commands.h"

namespace {

// Without a subcommand name, the arguments are those of `serve`.
std::vector<std::string> with_default_subcommand(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (!args.empty() && (args[0] == "-h" || args[0] == "--help" || args[0] == "--version"))
    return args;
  // A first word that is not an option names a subcommand (CLI11 reports unknown ones).
  if (!args.empty() && !args[0].empty() && args[0][0] != '-') return args;
  args.insert(args.begin(), "serve");
  return args;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"keel-worker: runs Keel pipeline stages, leased from a server or locally",
               "keel-worker"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "keel-worker 0.1.0");
  const std::vector<keel::worker::Subcommand> commands = {
      keel::worker::add_serve_command(app),
      keel::worker::add_run_command(app),
      keel::worker::add_ate_command(app),
      keel::worker::add_rpe_command(app),
      keel::worker::add_filter_command(app),
      keel::worker::add_metrics_command(app),
      keel::worker::add_compare_command(app),
      keel::worker::add_options_command(app),
      keel::worker::add_init_command(app),
  };

  std::vector<std::string> args = with_default_subcommand(argc, argv);
  std::reverse(args.begin(), args.end());  // CLI11 takes the arguments reversed
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? keel::worker::kExitOk : keel::worker::kExitUsage;
  }
  for (const auto& command : commands)
    if (command.app->parsed()) return command.main();
  return keel::worker::kExitUsage;
}
