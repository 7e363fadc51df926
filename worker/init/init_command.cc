#include "worker/init/init_command.h"

#include <CLI/CLI.hpp>

#include <fstream>

#include "worker/init/bag_survey.h"
#include "worker/init/mission_draft.h"
#include "worker/io/bag/bag_source.h"
#include "worker/io/display_path.h"

namespace keel::init {

namespace fs = std::filesystem;

int run_init(const InitArgs& args, std::ostream& out, std::ostream& err) {
  std::error_code ec;
  if (!fs::exists(args.bag, ec)) {
    err << "keel init: " << args.bag.string() << ": no such bag (a ROS1 .bag, a rosbag2 folder, "
        << "or a .mcap or .db3 file)\n";
    return 1;
  }
  if (fs::exists(args.output, ec) && !args.force) {
    err << "keel init: " << args.output.string() << " exists; give --force to replace it\n";
    return 1;
  }
  try {
    const auto bag = io::open_bag(args.bag);
    const BagSurvey survey = survey_bag(*bag);
    print_survey(survey, out);
    DraftOptions options;
    options.name = args.name;
    options.mission_folder = args.output.has_parent_path() ? args.output.parent_path() : ".";
    const MissionDraft draft = draft_mission(survey, options);
    {
      std::ofstream file(args.output);
      file << draft.yaml;
      if (!file.flush()) {
        err << "keel init: cannot write " << args.output.string() << "\n";
        return 1;
      }
    }
    out << "\nwrote " << args.output.string() << "\n";
    for (const auto& m : draft.missing) out << "missing: " << m << "\n";
    for (const auto& c : draft.confirm) out << "confirm: " << c << "\n";
  } catch (const std::exception& e) {
    err << "keel init: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

std::pair<CLI::App*, std::shared_ptr<InitArgs>> add_init_subcommand(CLI::App& app) {
  auto args = std::make_shared<InitArgs>();
  CLI::App* cmd = app.add_subcommand(
      "init", "Print a bag's topics and write a commented mission.yaml draft for it");
  cmd->add_option("bag", args->bag, "A ROS1 .bag, a rosbag2 folder, or a .mcap or .db3 file")
      ->required();
  cmd->add_option("-o,--output", args->output, "The draft to write (default mission.yaml)");
  cmd->add_option("--name", args->name, "Mission name (default: from the bag's name)");
  cmd->add_flag("--force", args->force, "Replace an existing output file");
  return {cmd, args};
}

}  // namespace keel::init
