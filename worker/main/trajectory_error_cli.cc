#include "worker/main/trajectory_error_cli.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "worker/main/commands.h"
#include "worker/main/trajectory_source.h"

namespace keel::worker {

namespace {

const char* kRule =
    "--------------------------------------------------------------------------------\n";

slam::Alignment resolve_alignment(const TrajectoryErrorArgs& args) {
  if (args.align_flag) {
    if (args.align != "none") throw std::invalid_argument("give either --align or -a/-s, not both");
    return args.scale_flag ? slam::Alignment::kSim3 : slam::Alignment::kSE3;
  }
  if (args.scale_flag)
    throw std::invalid_argument(
        "-s (scale correction) alone is not supported: use -as or --align sim3");
  if (args.align == "se3") return slam::Alignment::kSE3;
  if (args.align == "sim3") return slam::Alignment::kSim3;
  if (args.align == "none") return slam::Alignment::kNone;
  throw std::invalid_argument("--align " + args.align + ": expected se3, sim3 or none");
}

}  // namespace

void add_trajectory_error_options(CLI::App* cmd, TrajectoryErrorArgs* args) {
  cmd->add_option("--ref", args->ref, "Reference trajectory: FILE or BAG:TOPIC")->required();
  cmd->add_option("--est", args->est, "Estimated trajectory: FILE or BAG:TOPIC")->required();
  cmd->add_option("--format", args->format,
                  "File format: tum (t x y z qx qy qz qw) or kitti (12 numbers, index = time)")
      ->capture_default_str();
  cmd->add_option("--align", args->align, "Umeyama alignment: se3, sim3 or none")
      ->capture_default_str();
  cmd->add_flag("-a", args->align_flag, "As evo's -a: SE(3) alignment (-as: Sim(3))");
  cmd->add_flag("-s", args->scale_flag, "As evo's -s: with -a, correct the scale too");
  cmd->add_option("--t-max-diff", args->t_max_diff_s,
                  "Maximum time difference of associated stamps (s)")
      ->capture_default_str();
  cmd->add_option("--t-offset", args->t_offset_s, "Time offset added to the estimate's stamps (s)")
      ->capture_default_str();
  cmd->add_option("--pose-relation", args->pose_relation, "trans_part or angle_deg")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "Print the result as JSON");
}

bool relation_is_rotation(const TrajectoryErrorArgs& args) {
  if (args.pose_relation == "trans_part") return false;
  if (args.pose_relation == "angle_deg") return true;
  throw std::invalid_argument("--pose-relation " + args.pose_relation +
                              ": expected trans_part or angle_deg");
}

std::string alignment_title(slam::Alignment alignment) {
  switch (alignment) {
    case slam::Alignment::kSE3:
      return "(with SE(3) Umeyama alignment)";
    case slam::Alignment::kSim3:
      return "(with Sim(3) Umeyama alignment)";
    case slam::Alignment::kNone:
      break;
  }
  return "(not aligned)";
}

std::string alignment_name(slam::Alignment alignment) {
  switch (alignment) {
    case slam::Alignment::kSE3:
      return "se3";
    case slam::Alignment::kSim3:
      return "sim3";
    case slam::Alignment::kNone:
      break;
  }
  return "none";
}

PairedPoses load_paired_poses(const TrajectoryErrorArgs& args) {
  const TrajectoryFormat format = trajectory_format_from_string(args.format);
  if (!(args.t_max_diff_s >= 0.0) || !std::isfinite(args.t_offset_s))
    throw std::invalid_argument("--t-max-diff must be >= 0 and --t-offset finite");
  PairedPoses paired;
  paired.alignment = resolve_alignment(args);
  relation_is_rotation(args);
  const LoadedTrajectory ref = load_trajectory_argument(args.ref, format);
  const LoadedTrajectory est = load_trajectory_argument(args.est, format);
  paired.reference_source = ref.source;
  paired.estimate_source = est.source;
  paired.reference_count = ref.poses.size();
  paired.estimate_count = est.poses.size();
  std::ostringstream log;
  log << kRule << "Loaded " << ref.poses.size() << " stamps and poses from: " << ref.source << "\n"
      << "Loaded " << est.poses.size() << " stamps and poses from: " << est.source << "\n"
      << kRule;
  const bool by_index = format == TrajectoryFormat::kKitti &&
                        args.ref.find(".bag:") == std::string::npos &&
                        args.est.find(".bag:") == std::string::npos;
  if (by_index) {
    if (ref.poses.size() != est.poses.size())
      throw std::invalid_argument("KITTI poses are paired by index: " + ref.source + " has " +
                                  std::to_string(ref.poses.size()) + " poses, " + est.source +
                                  " has " + std::to_string(est.poses.size()));
    for (size_t k = 0; k < ref.poses.size(); ++k) {
      paired.reference.push_back(ref.poses[k].T_world_body);
      paired.estimate.push_back(est.poses[k].T_world_body);
    }
  } else {
    slam::AssociationOptions association;
    association.max_difference_s = args.t_max_diff_s;
    association.time_offset_s = args.t_offset_s;
    const slam::Association a = slam::associate_by_time(ref.poses, est.poses, association);
    log << "Found " << a.reference_index.size() << " of max. "
        << std::min(ref.poses.size(), est.poses.size())
        << " possible matching timestamps between...\n\t" << ref.source << "\nand:\t" << est.source
        << "\n..with max. time diff.: " << args.t_max_diff_s
        << " (s) and time offset: " << args.t_offset_s << " (s).\n"
        << kRule;
    if (a.reference_index.empty())
      throw std::invalid_argument("no matching timestamps between " + ref.source + " and " +
                                  est.source + " within " + std::to_string(args.t_max_diff_s) +
                                  " s (time offset " + std::to_string(args.t_offset_s) + " s)");
    for (size_t k = 0; k < a.reference_index.size(); ++k) {
      paired.reference.push_back(ref.poses[a.reference_index[k]].T_world_body);
      paired.estimate.push_back(est.poses[a.estimate_index[k]].T_world_body);
    }
  }
  if (paired.alignment != slam::Alignment::kNone) {
    if (paired.alignment == slam::Alignment::kSim3) log << "Correcting scale...\n";
    log << "Aligning using Umeyama's method...\n" << kRule;
  }
  paired.log = log.str();
  return paired;
}

void print_statistics(std::ostream& out, const slam::ErrorStatistics& s) {
  const double sse = s.rmse * s.rmse * static_cast<double>(s.count);
  const std::pair<const char*, double> rows[] = {
      {"max", s.max},   {"mean", s.mean}, {"median", s.median}, {"min", s.min},
      {"rmse", s.rmse}, {"sse", sse},     {"std", s.std}};
  char line[64];
  for (const auto& [name, value] : rows) {
    std::snprintf(line, sizeof(line), "%10s\t%f\n", name, value);
    out << line;
  }
}

nlohmann::ordered_json statistics_json(const slam::ErrorStatistics& s) {
  return {{"count", s.count}, {"rmse", s.rmse},
          {"mean", s.mean},   {"median", s.median},
          {"std", s.std},     {"min", s.min},
          {"max", s.max},     {"sse", s.rmse * s.rmse * static_cast<double>(s.count)}};
}

nlohmann::ordered_json alignment_json(const slam::SimilarityTransform& S) {
  nlohmann::ordered_json rotation = nlohmann::ordered_json::array();
  for (int r = 0; r < 3; ++r) rotation.push_back({S.R(r, 0), S.R(r, 1), S.R(r, 2)});
  return {{"rotation", rotation}, {"translation", {S.t.x(), S.t.y(), S.t.z()}}, {"scale", S.scale}};
}

int run_trajectory_tool(const std::string& name, const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    std::cerr << "keel-worker " << name << ": " << e.what() << "\n";
    return kExitUsage;
  }
}

}  // namespace keel::worker
