// `keel-worker rpe --ref FILE|BAG:TOPIC --est FILE|BAG:TOPIC [--delta 1] [--delta-unit f|m]
//  [--all-pairs] [--pose-relation trans_part|angle_deg] [--format tum|kitti]
//  [--align se3|sim3|none | -a [-s]] [--t-max-diff 0.01] [--t-offset 0] [--json]`:
// relative pose error as evo_rpe computes and prints it: E = (T_ref_i^-1 T_ref_j)^-1
// (T_est_i^-1 T_est_j) over pose pairs `delta` frames or metres of path apart.
// Exit codes: 0 done, 1 usage or unreadable input.
#include <iostream>
#include <memory>
#include <sstream>

#include "worker/main/commands.h"
#include "worker/main/trajectory_error_cli.h"

namespace keel::worker {

namespace {

struct RpeArgs {
  TrajectoryErrorArgs common;
  double delta = 1.0;
  std::string delta_unit = "f";
  bool all_pairs = false;
};

std::string format_delta(double delta) {
  std::ostringstream s;
  s << delta;
  return s.str();
}

int run_rpe(const RpeArgs& args) {
  slam::RpeOptions options;
  options.delta = args.delta;
  options.all_pairs = args.all_pairs;
  if (args.delta_unit == "f")
    options.unit = slam::DeltaUnit::kFrames;
  else if (args.delta_unit == "m")
    options.unit = slam::DeltaUnit::kMeters;
  else
    throw std::invalid_argument("--delta-unit " + args.delta_unit +
                                ": expected f (frames) or m (metres)");
  const PairedPoses paired = load_paired_poses(args.common);
  options.alignment = paired.alignment;
  const bool rotation = relation_is_rotation(args.common);
  const slam::RpeResult rpe = slam::relative_pose_error(paired.reference, paired.estimate, options);
  const slam::ErrorStatistics& stats = rotation ? rpe.rotation_deg : rpe.translation_m;
  const std::string unit = rotation ? "deg" : "m";
  const std::string unit_name = args.delta_unit == "f" ? "frames" : "m";
  const std::string pairs = args.all_pairs ? "all pairs" : "consecutive pairs";
  if (args.common.json) {
    nlohmann::ordered_json out = {{"metric", "rpe"},
                                  {"pose_relation", args.common.pose_relation},
                                  {"unit", unit},
                                  {"delta", args.delta},
                                  {"delta_unit", args.delta_unit},
                                  {"all_pairs", args.all_pairs},
                                  {"alignment", alignment_name(paired.alignment)},
                                  {"reference", paired.reference_source},
                                  {"estimate", paired.estimate_source},
                                  {"reference_poses", paired.reference_count},
                                  {"estimate_poses", paired.estimate_count},
                                  {"associated_poses", paired.reference.size()},
                                  {"pairs", rpe.pairs.size()}};
    out["statistics"] = statistics_json(stats);
    std::cout << out.dump(2) << std::endl;
    return kExitOk;
  }
  std::cout << paired.log << "Found " << rpe.pairs.size() << " pairs with delta "
            << format_delta(args.delta) << " (" << unit_name << ") among "
            << paired.reference.size() << " poses using " << pairs << ".\n"
            << "Compared " << rpe.pairs.size()
            << " relative pose pairs, delta = " << format_delta(args.delta) << " (" << unit_name
            << ") with " << pairs << ".\n"
            << "Calculating RPE for "
            << (rotation ? "rotation angle in degrees" : "translation part")
            << " pose relation...\n"
            << "--------------------------------------------------------------------------------\n"
            << "RPE w.r.t. " << (rotation ? "rotation angle in degrees" : "translation part")
            << " (" << unit << ")\nfor delta = " << format_delta(args.delta) << " (" << unit_name
            << ") using " << pairs << "\n"
            << alignment_title(paired.alignment) << "\n\n";
  print_statistics(std::cout, stats);
  std::cout << std::flush;
  return kExitOk;
}

}  // namespace

Subcommand add_rpe_command(CLI::App& app) {
  auto args = std::make_shared<RpeArgs>();
  CLI::App* cmd =
      app.add_subcommand("rpe", "Relative pose error of --est against --ref (as evo_rpe)");
  add_trajectory_error_options(cmd, &args->common);
  cmd->add_option("--delta", args->delta, "Distance between the poses of a pair")
      ->capture_default_str();
  cmd->add_option("--delta-unit", args->delta_unit, "f (frames) or m (metres of path)")
      ->capture_default_str();
  cmd->add_flag("--all-pairs", args->all_pairs,
                "Every start index instead of consecutive, non-overlapping pairs");
  return {cmd, [args] { return run_trajectory_tool("rpe", [&] { return run_rpe(*args); }); }};
}

}  // namespace keel::worker
