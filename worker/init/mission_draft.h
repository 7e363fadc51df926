// A commented mission.yaml draft from a bag survey (bag_survey.h): every topic Keel can read
// mapped to a sensor or a trajectory by its message type, rate_hz from the data, extrinsics
// from /tf_static (or /tf, said so), the point-time field recognised, and a comment on every
// choice the user must confirm. What a stage needs and the bag lacks is listed in the user's
// terms (`missing`), in the draft's head comment and for `keel init` to print.
//
// Message types mapped (docs/mission-format.md; issue 30 adds the last four):
//   sensor_msgs/Imu -> imu; geometry_msgs/TwistWithCovarianceStamped, TwistStamped -> dvl;
//   sensor_msgs/PointCloud2 -> lidar (sonar when the topic or frame says sonar);
//   sensor_msgs/Image, CompressedImage -> camera (commented out: needs intrinsics);
//   nav_msgs/Odometry, geometry_msgs/PoseStamped -> trajectories map / odometry /
//   ground_truth; tf2_msgs/TFMessage -> extrinsics;
//   waterlinked_a50_ros_driver/DVL, dvl_msgs/DVL -> dvl; velodyne_msgs/VelodyneScan -> lidar
//   with `packets:`; sensor_msgs/NavSatFix -> gnss with `origin:` at the first fix.
// Not mapped (Keel has no reader for them): everything else, e.g. sensor_msgs/FluidPressure
// (depth is read from depth.csv), CameraInfo, LaserScan, TF as a trajectory.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "worker/init/bag_survey.h"

namespace keel::init {

struct DraftOptions {
  std::string name;  // mission name; empty: the bag's file name
  // Folder the draft is written into: `bag:` is relative to it.
  std::filesystem::path mission_folder;
};

struct MissionDraft {
  std::string yaml;                  // the commented mission.yaml
  std::vector<std::string> missing;  // what stages need and the bag lacks, in the user's terms
  std::vector<std::string> confirm;  // choices the user must confirm (also comments in yaml)
};

MissionDraft draft_mission(const BagSurvey& survey, const DraftOptions& options);

}  // namespace keel::init
