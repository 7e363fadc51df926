// Decodes a message of one of the ROS 2 types Keel reads (ros2_messages.h, a50_messages.h), by
// type name;
// unknown types are left alone. For the fuzzers: every decoder must refuse bad bytes with
// BagFormatError and nothing else.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "worker/io/bag/a50_messages.h"
#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/ros2_messages.h"

namespace keel::fuzz {

inline void decode_as(std::string_view type, const uint8_t* data, size_t size) {
  namespace r = io::ros2;
  try {
    if (type == "sensor_msgs/msg/Imu") r::decode_imu(data, size);
    if (type == "sensor_msgs/msg/PointCloud2") r::decode_point_cloud2(data, size);
    if (type == "sensor_msgs/msg/Image") r::decode_image(data, size);
    if (type == "sensor_msgs/msg/CompressedImage") r::decode_compressed_image(data, size);
    if (type == "nav_msgs/msg/Odometry") r::decode_odometry(data, size);
    if (type == "geometry_msgs/msg/PoseStamped") r::decode_pose_stamped(data, size);
    if (type == "geometry_msgs/msg/TwistStamped") r::decode_twist_stamped(data, size);
    if (type == "geometry_msgs/msg/TwistWithCovarianceStamped")
      r::decode_twist_with_covariance_stamped(data, size);
    if (type == "tf2_msgs/msg/TFMessage") r::decode_tf_message(data, size);
    if (type == "dvl_msgs/msg/DVL") io::decode_a50_ros2(data, size);
    if (type == "sensor_msgs/msg/NavSatFix") r::decode_nav_sat_fix(data, size);
  } catch (const io::BagFormatError&) {
  }
}

inline constexpr const char* kTypes[] = {"sensor_msgs/msg/Imu",
                                         "sensor_msgs/msg/PointCloud2",
                                         "sensor_msgs/msg/Image",
                                         "sensor_msgs/msg/CompressedImage",
                                         "nav_msgs/msg/Odometry",
                                         "geometry_msgs/msg/PoseStamped",
                                         "geometry_msgs/msg/TwistStamped",
                                         "geometry_msgs/msg/TwistWithCovarianceStamped",
                                         "tf2_msgs/msg/TFMessage",
                                         "dvl_msgs/msg/DVL", "sensor_msgs/msg/NavSatFix"};

}  // namespace keel::fuzz
