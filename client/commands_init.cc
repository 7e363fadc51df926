// keel init BAG [-o mission.yaml]: prints the bag's topics and writes a commented mission.yaml
// draft, on the field laptop, before anything is uploaded (worker/init/init_command.h; the
// same as `keel-worker init`).
#include <iostream>
#include <memory>

#include "client/commands.h"
#include "worker/init/init_command.h"

namespace keel::client {

void add_init_command(CLI::App& app, CliContext& context) {
  const auto [cmd, added_args] = init::add_init_subcommand(app);
  const std::shared_ptr<init::InitArgs> args = added_args;
  cmd->callback(
      [&context, args] { context.exit_code = init::run_init(*args, std::cout, std::cerr); });
}

}  // namespace keel::client
