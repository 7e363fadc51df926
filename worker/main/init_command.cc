// `keel-worker init BAG [-o mission.yaml]`: the mission.yaml draft of `keel init`, offline
// (worker/init/init_command.h).
#include <iostream>
#include <memory>

#include "worker/init/init_command.h"
#include "worker/main/commands.h"

namespace keel::worker {

Subcommand add_init_command(CLI::App& app) {
  const auto [cmd, added_args] = init::add_init_subcommand(app);
  const std::shared_ptr<init::InitArgs> args = added_args;
  return {cmd, [args] { return init::run_init(*args, std::cout, std::cerr); }};
}

}  // namespace keel::worker
