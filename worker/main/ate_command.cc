// `keel-worker ate --ref FILE|BAG:TOPIC --est FILE|BAG:TOPIC [--format tum|kitti]
//  [--align se3|sim3|none | -a [-s]] [--t-max-diff 0.01] [--t-offset 0]
//  [--pose-relation trans_part|angle_deg] [--json]`:
// absolute trajectory error as evo_ape computes and prints it (Zhang & Scaramuzza, IROS 2018).
// Exit codes: 0 done, 1 usage or unreadable input.
#include <iostream>
#include <memory>

#include "worker/main/commands.h"
#include "worker/main/trajectory_error_cli.h"

namespace keel::worker {

namespace {

int run_ate(const TrajectoryErrorArgs& args) {
  const PairedPoses paired = load_paired_poses(args);
  const bool rotation = relation_is_rotation(args);
  const slam::AteResult ate =
      slam::absolute_trajectory_error(paired.reference, paired.estimate, paired.alignment);
  const slam::ErrorStatistics& stats = rotation ? ate.rotation_deg : ate.translation_m;
  const std::string relation = rotation ? "rotation angle in degrees" : "translation part";
  const std::string unit = rotation ? "deg" : "m";
  if (args.json) {
    nlohmann::ordered_json out = {{"metric", "ape"},
                                  {"pose_relation", args.pose_relation},
                                  {"unit", unit},
                                  {"alignment", alignment_name(paired.alignment)},
                                  {"reference", paired.reference_source},
                                  {"estimate", paired.estimate_source},
                                  {"reference_poses", paired.reference_count},
                                  {"estimate_poses", paired.estimate_count},
                                  {"pairs", paired.reference.size()}};
    out["statistics"] = statistics_json(stats);
    if (paired.alignment != slam::Alignment::kNone)
      out["alignment_transform"] = alignment_json(ate.alignment);
    std::cout << out.dump(2) << std::endl;
    return kExitOk;
  }
  std::cout << paired.log << "Compared " << paired.reference.size() << " absolute pose pairs.\n"
            << "Calculating APE for "
            << (rotation ? "rotation angle in degrees" : "translation part")
            << " pose relation...\n"
            << "--------------------------------------------------------------------------------\n"
            << "APE w.r.t. " << relation << " (" << unit << ")\n"
            << alignment_title(paired.alignment) << "\n\n";
  print_statistics(std::cout, stats);
  std::cout << std::flush;
  return kExitOk;
}

}  // namespace

Subcommand add_ate_command(CLI::App& app) {
  auto args = std::make_shared<TrajectoryErrorArgs>();
  CLI::App* cmd =
      app.add_subcommand("ate", "Absolute trajectory error of --est against --ref (as evo_ape)");
  add_trajectory_error_options(cmd, args.get());
  return {cmd, [args] { return run_trajectory_tool("ate", [&] { return run_ate(*args); }); }};
}

}  // namespace keel::worker
