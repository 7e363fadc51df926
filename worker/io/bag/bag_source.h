// A recorded bag seen as typed topics, whatever its format: a ROS1 bag (bag_reader.h) or a
// ROS 2 bag (rosbag2_reader.h: a rosbag2 folder, or one .mcap or .db3 file). Topics come out
// as the same typed values as the file readers: ImuSeries, DvlSeries, Trajectory, ScanSource
// (one PointCloud2 at a time), ImageSource, and static transforms from /tf_static.
// Stamps are the messages' header stamps (the bag's receive time when a header stamp is 0).
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/io/image_source.h"
#include "worker/io/scan_source.h"
#include "worker/io/stream_samples.h"

namespace keel::io {

struct BagTopicInfo {
  std::string topic;
  std::string datatype;  // as recorded: sensor_msgs/Imu (ROS1), sensor_msgs/msg/Imu (ROS 2)
  size_t messages = 0;
};

// One message as recorded, whatever its type, for tools that look at every topic (keel
// init): the recorder's receive time and the serialized bytes, ROS1 serialization or (ROS 2
// bags, `cdr`) CDR with its 4-byte encapsulation header.
struct BagRawMessage {
  std::string_view type;
  TimeNs log_time_ns = 0;
  const uint8_t* data = nullptr;
  size_t size = 0;
  bool cdr = false;
};

// One edge of the TF tree: T_parent_child maps points in `child_frame` into `parent_frame`.
struct StaticTransform {
  std::string parent_frame;
  std::string child_frame;
  Pose3 T_parent_child = Pose3::Identity();
};

class BagSource {
 public:
  virtual ~BagSource() = default;

  virtual const std::filesystem::path& path() const = 0;
  virtual const std::vector<BagTopicInfo>& topics() const = 0;
  // Fails naming the bag, the topic and the bag's topics when it is not in the bag.
  const BagTopicInfo& topic(const std::string& name) const;
  bool has_topic(const std::string& name) const;

  // Each fails naming bag, topic and message index on a wrong message type, a non-finite
  // value or a duplicate/decreasing stamp.
  virtual ImuSeries read_imu(const std::string& topic) const = 0;  // sensor_msgs/Imu
  // geometry_msgs/TwistWithCovarianceStamped or geometry_msgs/TwistStamped, or a Water Linked
  // A50's waterlinked_a50_ros_driver/DVL (ROS1) / dvl_msgs/msg/DVL (ROS 2): a50_dvl_sample.h.
  virtual DvlSeries read_dvl(const std::string& topic) const = 0;
  // sensor_msgs/NavSatFix: every message, no-fix ones included (status -1; nav_sat_fix.h).
  virtual GnssSeries read_gnss(const std::string& topic) const = 0;
  // geometry_msgs/PoseStamped or nav_msgs/Odometry
  virtual Trajectory read_trajectory(const std::string& topic) const = 0;
  // tf2_msgs/TFMessage; empty when the bag has no such topic.
  virtual std::vector<StaticTransform> read_static_transforms(
      const std::string& topic = "/tf_static") const = 0;
  // sensor_msgs/PointCloud2, one message at a time; the time field as in ScanReadOptions.
  virtual std::unique_ptr<ScanSource> open_scans(const std::string& topic,
                                                 ScanReadOptions options) const = 0;
  // sensor_msgs/Image (mono8/16, rgb8, bgr8, rgba8, bgra8) or sensor_msgs/CompressedImage.
  virtual std::unique_ptr<ImageSource> open_images(const std::string& topic) const = 0;
  // Every message of `topic` in recording order, undecoded (`body` may stop early by
  // returning false). Fails naming the bag and the topic.
  virtual void for_each_raw_message(
      const std::string& topic,
      const std::function<bool(const BagRawMessage&, size_t index)>& body) const = 0;

 protected:
  // Why topics may be missing (a file cut short), for the "no topic" error; "" when intact.
  virtual std::string damage() const { return ""; }
};

// Opens `path` by its form: a folder (rosbag2, with metadata.yaml), a .mcap or .db3 file
// (one ROS 2 storage file) or anything else as a ROS1 bag. Fails naming the path.
std::unique_ptr<BagSource> open_bag(const std::filesystem::path& path);

// Chains static transforms: T_target_source, or nothing when the frames are not connected.
// (A frame equal to itself gives the identity.)
bool lookup_static_transform(const std::vector<StaticTransform>& transforms,
                             const std::string& target_frame, const std::string& source_frame,
                             Pose3& T_target_source);

}  // namespace keel::io
