// ROS1 bags through Debian's rosbag_storage (no ROS install), kept out of this header. Topics
// come out as the same typed values as the file readers: ImuSeries, DvlSeries, Trajectory,
// ScanSource (one PointCloud2 at a time), ImageSource, and static transforms from /tf_static.
// Stamps are the messages' header stamps (the bag's receive time when a header stamp is 0).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "worker/core/pose.h"
#include "worker/io/image_source.h"
#include "worker/io/scan_source.h"
#include "worker/io/stream_samples.h"

namespace keel::io {

struct BagTopicInfo {
  std::string topic;
  std::string datatype;  // e.g. sensor_msgs/Imu
  size_t messages = 0;
};

// One edge of the TF tree: T_parent_child maps points in `child_frame` into `parent_frame`.
struct StaticTransform {
  std::string parent_frame;
  std::string child_frame;
  Pose3 T_parent_child = Pose3::Identity();
};

class BagReader {
 public:
  // Opens the bag and reads its index. A truncated or corrupt bag fails naming the bag.
  explicit BagReader(const std::filesystem::path& path);
  ~BagReader();

  const std::filesystem::path& path() const;
  const std::vector<BagTopicInfo>& topics() const;
  // Fails naming the topic and the bag's topics when it is not in the bag.
  const BagTopicInfo& topic(const std::string& name) const;
  bool has_topic(const std::string& name) const;

  // Each fails naming bag, topic and message index on a wrong message type, a non-finite
  // value or a duplicate/decreasing stamp.
  ImuSeries read_imu(const std::string& topic) const;  // sensor_msgs/Imu
  DvlSeries read_dvl(const std::string& topic) const;  // geometry_msgs/Twist(WithCovariance)Stamped
  Trajectory read_trajectory(const std::string& topic) const;  // PoseStamped or nav_msgs/Odometry
  std::vector<StaticTransform> read_static_transforms(
      const std::string& topic = "/tf_static") const;
  // sensor_msgs/PointCloud2, one message at a time; the time field as in ScanReadOptions.
  std::unique_ptr<ScanSource> open_scans(const std::string& topic, ScanReadOptions options) const;
  // sensor_msgs/Image (mono8/16, rgb8, bgr8, rgba8, bgra8) or sensor_msgs/CompressedImage.
  std::unique_ptr<ImageSource> open_images(const std::string& topic) const;

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;  // shared with open sources, which may outlive the reader
};

// Chains static transforms: T_target_source, or nothing when the frames are not connected.
// (A frame equal to itself gives the identity.)
bool lookup_static_transform(const std::vector<StaticTransform>& transforms,
                             const std::string& target_frame, const std::string& source_frame,
                             Pose3& T_target_source);

}  // namespace keel::io
