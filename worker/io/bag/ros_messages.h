// What Keel takes from the ROS message types of a bag, ROS1 or ROS 2 alike: PointCloud2 and
// Image contents as views into the message, their conversion into Keel's values, and the
// checks both bag readers apply (finite values, unit quaternions, increasing stamps).
// `what` names the message in errors: "<bag>: topic '/imu' message 17".
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>

#include "core/point_cloud.h"
#include "core/pose.h"
#include "worker/io/bag/ros_message_views.h"
#include "worker/io/cloud/packed_cloud.h"
#include "worker/io/image_source.h"
#include "worker/io/lidar/velodyne_packet.h"

namespace keel::io {

// Raw Velodyne packets (velodyne_msgs/VelodyneScan) on a lidar topic.
constexpr const char* kVelodyneScanRos1 = "velodyne_msgs/VelodyneScan";
constexpr const char* kVelodyneScanRos2 = "velodyne_msgs/msg/VelodyneScan";
// A packet topic needs `options.packets` (mission.yaml `packets:`), a PointCloud2 topic must
// not have it; fails naming the bag, the topic and what to write.
void check_packet_options(const std::string& bag, const std::string& topic, bool is_packets,
                          const ScanReadOptions& options);
// One serialised VelodyneScan (ROS 1, or CDR when `cdr`) decoded into one scan
// (lidar/velodyne_scan.h); `received_ns` (the bag's time) stands in for missing stamps.
PointCloud decode_velodyne_message(const uint8_t* data, size_t size, bool cdr, TimeNs received_ns,
                                   const ScanReadOptions& options, const std::string& what,
                                   std::vector<lidar::VelodynePoint>& scratch);

// Little-endian point records only; rows may be padded (row_step > width * point_step).
PointCloud unpack_point_cloud2(const PointCloud2View& msg, TimeNs t_ns,
                               const ScanReadOptions& options, const std::string& what);
// mono8/16, rgb8, bgr8, rgba8, bgra8 (and 8UC1/16UC1/8UC3/8UC4); sizes only unless `decode`.
ImageFrame unpack_image(const ImageView& msg, bool decode, const std::string& what);

Eigen::Vector3d finite_vector(double x, double y, double z, const std::string& what);
// A pose from a position and a quaternion that must be unit within 1e-3.
Pose3 checked_pose(const Eigen::Quaterniond& q, const Eigen::Vector3d& position,
                   const std::string& what);
// Stamps per topic must increase strictly; `index` 0 has no predecessor.
void check_increasing(const std::string& what, size_t index, TimeNs t_ns, TimeNs previous_ns);

}  // namespace keel::io
