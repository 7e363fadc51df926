// The ROS1 message types Keel reads, decoded from their ROS1 serialisation (ros1_reader.h)
// with every length checked, into the same values as their ROS 2 decoders (ros2_messages.h):
// sensor_msgs/{Imu, NavSatFix, PointCloud2, Image, CompressedImage}, nav_msgs/Odometry,
// geometry_msgs/{PoseStamped, TwistWithCovarianceStamped, TwistStamped} and
// tf2_msgs/TFMessage. Layouts: the .msg files of ROS1 common_msgs (Noetic), whose MD5 sums
// below a bag's connection records must declare. Each decoder reads every field, so a message
// cut anywhere is refused. Views point into the message bytes. Errors are BagFormatError
// naming the field.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "worker/io/bag/ros2_messages.h"

namespace keel::io::ros1 {

// The decoded values are ROS-version neutral (stamps in ns, views into the bytes).
using ros2::CompressedImage;
using ros2::Image;
using ros2::Imu;
using ros2::NavSatFix;
using ros2::PointCloud2;
using ros2::Pose;
using ros2::Transform;
using ros2::Twist;

// The MD5 sum of a message type's definition (genmsg), as rosbag's connection records carry
// it; "" for a type Keel does not decode.
std::string_view md5_of(std::string_view datatype);

Imu decode_imu(const uint8_t* data, size_t size);
NavSatFix decode_nav_sat_fix(const uint8_t* data, size_t size);
Twist decode_twist_stamped(const uint8_t* data, size_t size);
Twist decode_twist_with_covariance_stamped(const uint8_t* data, size_t size);
Pose decode_pose_stamped(const uint8_t* data, size_t size);
Pose decode_odometry(const uint8_t* data, size_t size);
std::vector<Transform> decode_tf_message(const uint8_t* data, size_t size);
PointCloud2 decode_point_cloud2(const uint8_t* data, size_t size);
Image decode_image(const uint8_t* data, size_t size);
CompressedImage decode_compressed_image(const uint8_t* data, size_t size);

}  // namespace keel::io::ros1
