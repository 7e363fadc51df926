// The ROS 2 message types Keel reads, decoded from CDR (cdr_reader.h) with every length
// checked: sensor_msgs/msg/{Imu, NavSatFix, PointCloud2, Image, CompressedImage},
// nav_msgs/msg/Odometry, geometry_msgs/msg/{PoseStamped, TwistWithCovarianceStamped, TwistStamped}
// and tf2_msgs/msg/TFMessage. Layouts: the .msg files of ROS 2 common_interfaces (unchanged from
// Foxy to Jazzy). Views (PointCloud2View, ImageView, CompressedImage data) point into the
// message bytes. Errors are BagFormatError naming the field.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.h"
#include "worker/io/bag/ros_message_views.h"

namespace keel::io::ros2 {

// std_msgs/msg/Header.stamp in ns (0 when the publisher left it unset).
struct Imu {
  TimeNs stamp_ns = 0;
  Eigen::Vector3d angular_velocity, linear_acceleration;
};
struct Twist {  // the linear part of TwistStamped / TwistWithCovarianceStamped
  TimeNs stamp_ns = 0;
  Eigen::Vector3d linear;
};
struct Pose {  // PoseStamped.pose / Odometry.pose.pose
  TimeNs stamp_ns = 0;
  Eigen::Vector3d position;
  Eigen::Quaterniond orientation;
};
struct Transform {  // one geometry_msgs/msg/TransformStamped of a TFMessage
  std::string parent_frame, child_frame;
  Eigen::Vector3d translation;
  Eigen::Quaterniond rotation;
};
struct NavSatFix {  // sensor_msgs/msg/NavSatFix
  TimeNs stamp_ns = 0;
  int status = 0;  // NavSatStatus.status (int8): -1 no fix .. 2 GBAS fix
  double latitude_deg = 0.0, longitude_deg = 0.0, altitude_m = 0.0;
  std::array<double, 9> position_covariance{};  // ENU, m^2, row-major
  int position_covariance_type = 0;             // 0 unknown, 1 approximated, 2 diagonal, 3 known
};
struct PointCloud2 {
  TimeNs stamp_ns = 0;
  PointCloud2View view;
};
struct Image {
  TimeNs stamp_ns = 0;
  ImageView view;
};
struct CompressedImage {
  TimeNs stamp_ns = 0;
  std::string_view format;  // "png", "jpeg", "bgr8; jpeg compressed bgr8", ...
  const uint8_t* data = nullptr;
  size_t size = 0;
};

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

}  // namespace keel::io::ros2
