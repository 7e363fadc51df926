// `keel init BAG [-o mission.yaml]` and `keel-worker init` (one implementation, both CLIs call
// it): surveys the bag (bag_survey.h), prints its topic table, writes the commented
// mission.yaml draft (mission_draft.h) and lists what the user must confirm or add.
#pragma once

#include <filesystem>
#include <memory>
#include <ostream>
#include <string>
#include <utility>

namespace CLI {
class App;
}

namespace keel::init {

struct InitArgs {
  std::filesystem::path bag;
  std::filesystem::path output = "mission.yaml";
  std::string name;    // mission name; empty: from the bag's name
  bool force = false;  // overwrite an existing output
};

// Returns the exit code: 0 written, 1 bad arguments or an unreadable bag (message on `err`).
int run_init(const InitArgs& args, std::ostream& out, std::ostream& err);

// Adds the `init` subcommand's arguments to `app` (the same for `keel` and `keel-worker`);
// the returned arguments are filled when the command line is parsed.
std::pair<CLI::App*, std::shared_ptr<InitArgs>> add_init_subcommand(CLI::App& app);

}  // namespace keel::init
