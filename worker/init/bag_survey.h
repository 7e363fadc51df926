// One pass over every message of a bag (one message in memory at a time): per topic its type,
// message count, header stamps (the receive time where a type has no header), measured rate,
// time span, gaps, frame_id, and per type what a mission draft needs (PointCloud2 fields and
// point-time field, image encoding and size, Odometry's child frame, the first GNSS fix,
// the Velodyne packets' factory bytes). Plus the TF edges of /tf_static (or /tf).
#pragma once

#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "worker/init/point_time_guess.h"
#include "worker/init/raw_messages.h"
#include "worker/io/bag/bag_source.h"

namespace keel::init {

struct TopicSurvey {
  std::string topic;
  std::string type;        // as recorded
  std::string plain_type;  // "sensor_msgs/Imu" for ROS1 and ROS 2 alike
  size_t messages = 0;
  bool header_stamps = false;  // false: stamps are the recorder's receive times
  TimeNs first_ns = 0, last_ns = 0;
  double rate_hz = 0.0;    // (messages - 1) / span
  size_t gaps = 0;         // intervals longer than 2.5 median intervals
  double max_gap_s = 0.0;  // the longest interval
  std::string frame_id;    // of the first message
  std::string error;       // a message that could not be read ("" when all were)

  std::vector<std::pair<std::string, std::string>> fields;  // PointCloud2: name, type
  std::optional<PointTimeGuess> point_time;                 // PointCloud2
  std::optional<ImageInfo> image;                           // Image / CompressedImage
  std::string child_frame;                                  // Odometry
  std::optional<Fix> first_fix;                             // NavSatFix: the first with a fix
  std::optional<VelodyneFactory> velodyne;                  // VelodyneScan

  double span_s() const { return ns_to_seconds(last_ns - first_ns); }
};

struct BagSurvey {
  std::filesystem::path bag;
  std::vector<TopicSurvey> topics;  // in the bag's topic order
  std::vector<io::StaticTransform> transforms;
  std::string transforms_topic;  // "/tf_static", "/tf", or "" when neither exists
};

BagSurvey survey_bag(const io::BagSource& bag);

// The table `keel init` prints: one row per topic, then per-type details.
void print_survey(const BagSurvey& survey, std::ostream& out);

}  // namespace keel::init
