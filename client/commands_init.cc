// keel init BAG [-o mission.yaml]: prints the bag's topics and writes a commented mission.yaml
// draft, on the field laptop, before anything is uploaded (worker/init/init_command.h; the
// same as `keel-worker init`).
#include <iostream>
#include <memory>

#include "client/commands.h"
#include "worker/init/init_command.h"

namespace keel::client {

void add_init_command(CLI::App& app, CliContext& context) {
  auto args = std::make_shared<init::InitArgs>();
  CLI::App* cmd = app.add_subcommand(
      "init", "Print a bag's topics and write a commented mission.yaml draft for it");
  cmd->add_option("bag", args->bag, "A ROS1 .bag, a rosbag2 folder, or a .mcap or .db3 file")
      ->required();
  cmd->add_option("-o,--output", args->output, "The draft to write (default mission.yaml)");
  cmd->add_option("--name", args->name, "Mission name (default: from the bag's name)");
  cmd->add_flag("--force", args->force, "Replace an existing output file");
  cmd->callback(
      [&context, args] { context.exit_code = init::run_init(*args, std::cout, std::cerr); });
}

}  // namespace keel::client
