// `keel init BAG [-o mission.yaml]` and `keel-worker init` (one implementation, both CLIs call
// it): surveys the bag (bag_survey.h), prints its topic table, writes the commented
// mission.yaml draft (mission_draft.h) and lists what the user must confirm or add.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>

namespace keel::init {

struct InitArgs {
  std::filesystem::path bag;
  std::filesystem::path output = "mission.yaml";
  std::string name;    // mission name; empty: from the bag's name
  bool force = false;  // overwrite an existing output
};

// Returns the exit code: 0 written, 1 bad arguments or an unreadable bag (message on `err`).
int run_init(const InitArgs& args, std::ostream& out, std::ostream& err);

}  // namespace keel::init
