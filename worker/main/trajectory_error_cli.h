// What `keel-worker ate` and `keel-worker rpe` share: the evo-style options (--ref, --est,
// --format, --align / -a -s, --t-max-diff, --t-offset, --pose-relation, --json), loading and
// pairing the two trajectories, and printing statistics in evo's layout.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <ostream>
#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/slam/trajectory_metrics.h"

namespace keel::worker {

struct TrajectoryErrorArgs {
  std::string ref;
  std::string est;
  std::string format = "tum";
  std::string align = "none";  // se3 | sim3 | none
  bool align_flag = false;     // evo's -a
  bool scale_flag = false;     // evo's -s (with -a: Sim(3))
  double t_max_diff_s = 0.01;
  double t_offset_s = 0.0;
  std::string pose_relation = "trans_part";  // trans_part | angle_deg
  bool json = false;
};

// Registers the shared options on `cmd`.
void add_trajectory_error_options(CLI::App* cmd, TrajectoryErrorArgs* args);

// The two trajectories' poses paired (same index = same time), and what was done to pair them.
struct PairedPoses {
  std::vector<Pose3> reference;
  std::vector<Pose3> estimate;
  std::string reference_source, estimate_source;
  size_t reference_count = 0, estimate_count = 0;
  slam::Alignment alignment = slam::Alignment::kNone;
  std::string log;  // evo-style lines about loading and association
};

// Loads and pairs: KITTI files by index (equal counts required), others by evo's timestamp
// association. Throws std::invalid_argument naming the problem.
PairedPoses load_paired_poses(const TrajectoryErrorArgs& args);

bool relation_is_rotation(const TrajectoryErrorArgs& args);  // angle_deg; throws on bad names
std::string alignment_title(slam::Alignment alignment);      // "(with SE(3) Umeyama alignment)"
std::string alignment_name(slam::Alignment alignment);       // "se3"

// "       max\t1.234567" lines for max, mean, median, min, rmse, sse, std (evo's order).
void print_statistics(std::ostream& out, const slam::ErrorStatistics& stats);
nlohmann::ordered_json statistics_json(const slam::ErrorStatistics& stats);
nlohmann::ordered_json alignment_json(const slam::SimilarityTransform& transform);

// Runs `body` and turns its exceptions into "keel-worker <name>: message" and exit code 1.
int run_trajectory_tool(const std::string& name, const std::function<int()>& body);

}  // namespace keel::worker
