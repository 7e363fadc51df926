// Keel's ROS1 message decoders against roscpp's own serializer (an independent writer): every
// message of each type Keel reads, serialized by roscpp with non-empty strings and arrays,
// decodes to the values it was made of; every shorter prefix of it is refused (so the decoder
// reads exactly the bytes roscpp wrote); a length prefix that declares more than the message
// holds is refused naming the field, before anything that size is allocated. The MD5 sums
// Keel expects are roscpp's.
#include "worker/io/bag/ros1_messages.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <gtest/gtest.h>

#include <deque>
#include <nav_msgs/Odometry.h>
#include <ros/serialization.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cstring>
#include <vector>

#include "worker/io/bag/bag_format_error.h"

namespace keel::io {
namespace {

constexpr TimeNs kStampNs = 1700000000LL * 1000000000 + 5;

template <typename T>
std::vector<uint8_t> serialize(const T& message) {
  std::vector<uint8_t> bytes(ros::serialization::serializationLength(message));
  ros::serialization::OStream out(bytes.data(), static_cast<uint32_t>(bytes.size()));
  ros::serialization::serialize(out, message);
  return bytes;
}

// Decoded messages point into their bytes (frame ids, point and pixel data): every message's
// bytes are kept for the whole test.
std::deque<std::vector<uint8_t>>& kept_bytes() {
  static std::deque<std::vector<uint8_t>> bytes;
  return bytes;
}

// Decodes roscpp's bytes with `decode` (returned for the caller to compare) and checks that
// every prefix is refused and the MD5 Keel expects is roscpp's.
template <typename T, typename Decode>
auto decode_exact(const T& message, Decode decode) {
  const std::string type = ros::message_traits::datatype<T>();
  SCOPED_TRACE(type);
  EXPECT_EQ(ros1::md5_of(type), ros::message_traits::md5sum<T>());
  const std::vector<uint8_t>& bytes = kept_bytes().emplace_back(serialize(message));
  for (size_t n = 0; n < bytes.size(); ++n) {
    const std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + n);
    EXPECT_THROW(decode(prefix.data(), prefix.size()), BagFormatError) << "prefix of " << n;
  }
  return decode(bytes.data(), bytes.size());
}

std_msgs::Header header() {
  std_msgs::Header h;
  h.seq = 7;
  h.stamp = ros::Time(1700000000, 5);
  h.frame_id = "base_link";
  return h;
}

sensor_msgs::PointCloud2 cloud() {
  sensor_msgs::PointCloud2 c;
  c.header = header();
  c.height = 1;
  c.width = 2;
  for (const char* name : {"x", "y", "z", "intensity"}) {
    sensor_msgs::PointField f;
    f.name = name;
    f.offset = static_cast<uint32_t>(4 * c.fields.size());
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    c.fields.push_back(f);
  }
  c.point_step = 16;
  c.row_step = 32;
  for (int i = 0; i < 32; ++i) c.data.push_back(static_cast<uint8_t>(i));
  c.is_dense = true;
  return c;
}

TEST(Ros1Messages, DecodeExactlyWhatRoscppSerializes) {
  sensor_msgs::Imu imu;
  imu.header = header();
  imu.angular_velocity.x = 0.1, imu.angular_velocity.y = -0.2, imu.angular_velocity.z = 0.3;
  imu.linear_acceleration.x = 1, imu.linear_acceleration.y = 2, imu.linear_acceleration.z = 9.8;
  imu.orientation_covariance[8] = 5;  // a value to skip, not to read as acceleration
  const ros1::Imu i = decode_exact(imu, ros1::decode_imu);
  EXPECT_EQ(i.stamp_ns, kStampNs);
  EXPECT_EQ(i.angular_velocity, Eigen::Vector3d(0.1, -0.2, 0.3));
  EXPECT_EQ(i.linear_acceleration, Eigen::Vector3d(1, 2, 9.8));

  sensor_msgs::NavSatFix fix;
  fix.header = header();
  fix.status.status = -1;
  fix.status.service = 1;
  fix.latitude = 59.9, fix.longitude = 10.7, fix.altitude = 12.5;
  for (int k = 0; k < 9; ++k) fix.position_covariance[k] = k;
  fix.position_covariance_type = 2;
  const ros1::NavSatFix f = decode_exact(fix, ros1::decode_nav_sat_fix);
  EXPECT_EQ(f.stamp_ns, kStampNs);
  EXPECT_EQ(f.status, -1);
  EXPECT_EQ(f.latitude_deg, 59.9);
  EXPECT_EQ(f.longitude_deg, 10.7);
  EXPECT_EQ(f.altitude_m, 12.5);
  EXPECT_EQ(f.position_covariance[7], 7.0);
  EXPECT_EQ(f.position_covariance_type, 2);

  geometry_msgs::TwistWithCovarianceStamped twist_cov;
  twist_cov.header = header();
  twist_cov.twist.twist.linear.x = 0.5, twist_cov.twist.twist.linear.z = -0.25;
  twist_cov.twist.twist.angular.x = 3;
  const ros1::Twist tc = decode_exact(twist_cov, ros1::decode_twist_with_covariance_stamped);
  EXPECT_EQ(tc.linear, Eigen::Vector3d(0.5, 0, -0.25));
  geometry_msgs::TwistStamped twist;
  twist.header = header();
  twist.twist.linear.y = 1.5;
  EXPECT_EQ(decode_exact(twist, ros1::decode_twist_stamped).linear, Eigen::Vector3d(0, 1.5, 0));

  geometry_msgs::PoseStamped pose;
  pose.header = header();
  pose.pose.position.x = 1, pose.pose.position.y = 2, pose.pose.position.z = 3;
  pose.pose.orientation.x = 0.5, pose.pose.orientation.y = 0.5, pose.pose.orientation.z = 0.5;
  pose.pose.orientation.w = 0.5;
  const ros1::Pose p = decode_exact(pose, ros1::decode_pose_stamped);
  EXPECT_EQ(p.stamp_ns, kStampNs);
  EXPECT_EQ(p.position, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(p.orientation.coeffs(), Eigen::Vector4d(0.5, 0.5, 0.5, 0.5));  // x, y, z, w
  nav_msgs::Odometry odometry;
  odometry.header = header();
  odometry.child_frame_id = "imu";
  odometry.pose.pose = pose.pose;
  odometry.twist.twist.linear.x = 9;
  const ros1::Pose o = decode_exact(odometry, ros1::decode_odometry);
  EXPECT_EQ(o.position, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(o.orientation.w(), 0.5);

  const sensor_msgs::PointCloud2 c = cloud();
  const ros1::PointCloud2 pc = decode_exact(c, ros1::decode_point_cloud2);
  EXPECT_EQ(pc.stamp_ns, kStampNs);
  EXPECT_EQ(pc.view.width, 2u);
  EXPECT_EQ(pc.view.height, 1u);
  ASSERT_EQ(pc.view.fields.size(), 4u);
  EXPECT_EQ(pc.view.fields[3].name, "intensity");
  EXPECT_EQ(pc.view.fields[3].offset, 12u);
  EXPECT_EQ(pc.view.fields[3].datatype, sensor_msgs::PointField::FLOAT32);
  EXPECT_EQ(pc.view.point_step, 16u);
  EXPECT_EQ(pc.view.row_step, 32u);
  ASSERT_EQ(pc.view.data_size, 32u);

  sensor_msgs::Image image;
  image.header = header();
  image.height = 2;
  image.width = 3;
  image.encoding = "mono8";
  image.step = 3;
  image.data.assign(6, 9);
  const ros1::Image im = decode_exact(image, ros1::decode_image);
  EXPECT_EQ(im.view.encoding, "mono8");
  EXPECT_EQ(im.view.height, 2u);
  EXPECT_EQ(im.view.width, 3u);
  EXPECT_EQ(im.view.step, 3u);
  EXPECT_EQ(im.view.data_size, 6u);
  sensor_msgs::CompressedImage compressed;
  compressed.header = header();
  compressed.format = "png";
  compressed.data.assign(40, 1);
  const ros1::CompressedImage ci = decode_exact(compressed, ros1::decode_compressed_image);
  EXPECT_EQ(ci.format, "png");
  EXPECT_EQ(ci.size, 40u);

  tf2_msgs::TFMessage tf;
  for (const char* child : {"lidar", "camera_optical"}) {
    geometry_msgs::TransformStamped t;
    t.header = header();
    t.child_frame_id = child;
    t.transform.translation.x = 0.25 * static_cast<double>(tf.transforms.size() + 1);
    t.transform.rotation.w = 1;
    tf.transforms.push_back(t);
  }
  const std::vector<ros1::Transform> ts = decode_exact(tf, ros1::decode_tf_message);
  ASSERT_EQ(ts.size(), 2u);
  EXPECT_EQ(ts[1].parent_frame, "base_link");
  EXPECT_EQ(ts[1].child_frame, "camera_optical");
  EXPECT_EQ(ts[1].translation, Eigen::Vector3d(0.5, 0, 0));
  EXPECT_EQ(ts[1].rotation.w(), 1.0);
}

// fuzz_bag's input: a PointCloud2 whose `data` declared 4 GiB, which roscpp allocated.
TEST(Ros1Messages, ADataLengthBeyondTheMessageIsNamed) {
  std::vector<uint8_t> bytes = serialize(cloud());
  const size_t data_count = bytes.size() - 1 - 32 - 4;  // before data (32 bytes) and is_dense
  uint32_t declared;
  std::memcpy(&declared, bytes.data() + data_count, 4);
  ASSERT_EQ(declared, 32u);
  const uint32_t huge = 0xffffffffu;
  std::memcpy(bytes.data() + data_count, &huge, 4);
  try {
    (void)ros1::decode_point_cloud2(bytes.data(), bytes.size());
    FAIL() << "accepted";
  } catch (const BagFormatError& e) {
    EXPECT_EQ(std::string(e.what()), "ROS1: field 'data' needs 4294967295 bytes at offset " +
                                         std::to_string(data_count + 4) + "; the " +
                                         std::to_string(bytes.size()) +
                                         "-byte message has 33 left");
  }
}

}  // namespace
}  // namespace keel::io
