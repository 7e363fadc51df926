// `keel-worker init BAG [-o mission.yaml]`: the mission.yaml draft of `keel init`, offline
// (worker/init/init_command.h).
#include <iostream>
#include <memory>

#include "worker/init/init_command.h"
#include "worker/main/commands.h"

namespace keel::worker {

Subcommand add_init_command(CLI::App& app) {
  auto args = std::make_shared<init::InitArgs>();
  std::string bag, output = "mission.yaml";
  CLI::App* cmd = app.add_subcommand(
      "init", "Print a bag's topics and write a commented mission.yaml draft for it");
  cmd->add_option("bag", args->bag, "A ROS1 .bag, a rosbag2 folder, or a .mcap or .db3 file")
      ->required();
  cmd->add_option("-o,--output", args->output, "The draft to write (default mission.yaml)");
  cmd->add_option("--name", args->name, "Mission name (default: from the bag's name)");
  cmd->add_flag("--force", args->force, "Replace an existing output file");
  return {cmd, [args] { return init::run_init(*args, std::cout, std::cerr); }};
}

}  // namespace keel::worker
