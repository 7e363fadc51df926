#include "tests/sim/bag_writer.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cstring>
#include <stdexcept>

namespace keel::sim {
namespace {

ros::Time to_ros(TimeNs t_ns) {
  ros::Time t;
  t.fromNSec(static_cast<uint64_t>(t_ns));
  return t;
}

std_msgs::Header header(const std::string& frame, TimeNs t_ns) {
  std_msgs::Header h;
  h.stamp = to_ros(t_ns);
  h.frame_id = frame;
  return h;
}

geometry_msgs::Pose to_msg(const Pose3& T) {
  geometry_msgs::Pose p;
  const Eigen::Quaterniond q(T.linear());
  p.position.x = T.translation().x(), p.position.y = T.translation().y(),
  p.position.z = T.translation().z();
  p.orientation.x = q.x(), p.orientation.y = q.y(), p.orientation.z = q.z(),
  p.orientation.w = q.w();
  return p;
}

}  // namespace

struct BagWriter::Impl {
  rosbag::Bag bag;
};

BagWriter::BagWriter(const std::string& path, BagCompression compression)
    : impl_(std::make_unique<Impl>()) {
  try {
    impl_->bag.open(path, rosbag::bagmode::Write);
    if (compression == BagCompression::kBz2) impl_->bag.setCompression(rosbag::compression::BZ2);
    if (compression == BagCompression::kLz4) impl_->bag.setCompression(rosbag::compression::LZ4);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot write bag " + path + ": " + e.what());
  }
}

BagWriter::~BagWriter() {
  try {
    close();
  } catch (...) {
  }
}

void BagWriter::imu(const std::string& topic, const std::string& frame, TimeNs t_ns,
                    const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) {
  sensor_msgs::Imu m;
  m.header = header(frame, t_ns);
  m.orientation_covariance[0] = -1.0;  // no orientation estimate
  m.angular_velocity.x = gyro.x(), m.angular_velocity.y = gyro.y(), m.angular_velocity.z = gyro.z();
  m.linear_acceleration.x = accel.x(), m.linear_acceleration.y = accel.y(),
  m.linear_acceleration.z = accel.z();
  impl_->bag.write(topic, m.header.stamp, m);
}

void BagWriter::twist(const std::string& topic, const std::string& frame, TimeNs t_ns,
                      const Eigen::Vector3d& v, double sigma) {
  geometry_msgs::TwistWithCovarianceStamped m;
  m.header = header(frame, t_ns);
  m.twist.twist.linear.x = v.x(), m.twist.twist.linear.y = v.y(), m.twist.twist.linear.z = v.z();
  for (int i = 0; i < 3; ++i) m.twist.covariance[i * 7] = sigma * sigma;
  for (int i = 3; i < 6; ++i) m.twist.covariance[i * 7] = -1.0;  // angular part unknown
  impl_->bag.write(topic, m.header.stamp, m);
}

void BagWriter::cloud(const std::string& topic, const std::string& frame, const PointCloud& cloud) {
  sensor_msgs::PointCloud2 m;
  m.header = header(frame, cloud.t_ns);
  auto field = [&m](const std::string& name, uint32_t offset, uint8_t type) {
    sensor_msgs::PointField f;
    f.name = name, f.offset = offset, f.datatype = type, f.count = 1;
    m.fields.push_back(f);
  };
  uint32_t offset = 0;
  for (const char* axis : {"x", "y", "z"})
    field(axis, offset, sensor_msgs::PointField::FLOAT32), offset += 4;
  if (cloud.has_intensity())
    field("intensity", offset, sensor_msgs::PointField::FLOAT32), offset += 4;
  if (cloud.has_ring()) field("ring", offset, sensor_msgs::PointField::UINT16), offset += 2;
  if (cloud.has_time()) field("time", offset, sensor_msgs::PointField::FLOAT32), offset += 4;
  m.height = 1;
  m.width = static_cast<uint32_t>(cloud.size());
  m.is_bigendian = false;
  m.point_step = offset;
  m.row_step = offset * m.width;
  m.is_dense = true;
  m.data.resize(m.row_step);
  uint8_t* out = m.data.data();
  for (size_t i = 0; i < cloud.size(); ++i) {
    std::memcpy(out, cloud.xyz[i].data(), 12), out += 12;
    if (cloud.has_intensity()) std::memcpy(out, &cloud.intensity[i], 4), out += 4;
    if (cloud.has_ring()) std::memcpy(out, &cloud.ring[i], 2), out += 2;
    if (cloud.has_time()) std::memcpy(out, &cloud.time_s[i], 4), out += 4;
  }
  impl_->bag.write(topic, m.header.stamp, m);
}

void BagWriter::image(const std::string& topic, const std::string& frame, TimeNs t_ns,
                      const cv::Mat& gray) {
  sensor_msgs::Image m;
  m.header = header(frame, t_ns);
  m.height = gray.rows, m.width = gray.cols;
  m.encoding = "mono8";
  m.is_bigendian = 0;
  m.step = gray.cols;
  m.data.resize(static_cast<size_t>(gray.rows) * gray.cols);
  for (int r = 0; r < gray.rows; ++r)
    std::memcpy(&m.data[size_t(r) * gray.cols], gray.ptr(r), gray.cols);
  impl_->bag.write(topic, m.header.stamp, m);
}

void BagWriter::pose(const std::string& topic, const std::string& frame, const StampedPose& p) {
  geometry_msgs::PoseStamped m;
  m.header = header(frame, p.t_ns);
  m.pose = to_msg(p.T_world_body);
  impl_->bag.write(topic, m.header.stamp, m);
}

void BagWriter::odometry(const std::string& topic, const std::string& frame,
                         const std::string& child_frame, const StampedPose& p) {
  nav_msgs::Odometry m;
  m.header = header(frame, p.t_ns);
  m.child_frame_id = child_frame;
  m.pose.pose = to_msg(p.T_world_body);
  impl_->bag.write(topic, m.header.stamp, m);
}

void BagWriter::transforms(const std::string& topic, TimeNs t_ns, const TransformEdges& edges) {
  tf2_msgs::TFMessage m;
  for (const auto& [parent, child, T] : edges) {
    geometry_msgs::TransformStamped e;
    e.header = header(parent, t_ns);
    e.child_frame_id = child;
    const Eigen::Quaterniond q(T.linear());
    e.transform.translation.x = T.translation().x();
    e.transform.translation.y = T.translation().y();
    e.transform.translation.z = T.translation().z();
    e.transform.rotation.x = q.x();
    e.transform.rotation.y = q.y();
    e.transform.rotation.z = q.z();
    e.transform.rotation.w = q.w();
    m.transforms.push_back(e);
  }
  impl_->bag.write(topic, header("", t_ns).stamp, m);
}

void BagWriter::close() {
  if (impl_ && impl_->bag.isOpen()) impl_->bag.close();
}

}  // namespace keel::sim
