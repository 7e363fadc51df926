#include "worker/init/init_command.h"

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

}  // namespace keel::init
