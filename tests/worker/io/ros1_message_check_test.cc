// The ROS1 message check against roscpp's own serializer: every message of each type Keel
// reads, serialized by roscpp with non-empty strings and arrays, passes; every shorter prefix
// of it is refused (so the check walks exactly the bytes roscpp wrote); a length prefix that
// declares more than the message holds is refused naming the field.
#include "worker/io/bag/ros1_message_check.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/serialization.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cstring>
#include <vector>

#include "worker/io/io_error.h"

namespace keel::io {
namespace {

template <typename T>
std::vector<uint8_t> serialize(const T& message) {
  std::vector<uint8_t> bytes(ros::serialization::serializationLength(message));
  ros::serialization::OStream out(bytes.data(), static_cast<uint32_t>(bytes.size()));
  ros::serialization::serialize(out, message);
  return bytes;
}

template <typename T>
void expect_exact(const T& message) {
  const std::string type = ros::message_traits::datatype<T>();
  SCOPED_TRACE(type);
  const std::vector<uint8_t> bytes = serialize(message);
  EXPECT_NO_THROW(check_ros1_message(type, bytes.data(), bytes.size(), "m"));
  for (size_t n = 0; n < bytes.size(); ++n)
    EXPECT_THROW(check_ros1_message(type, bytes.data(), n, "m"), IoError) << "prefix of " << n;
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
  c.data.assign(32, 3);
  c.is_dense = true;
  return c;
}

TEST(Ros1MessageCheck, WalksExactlyWhatRoscppSerializes) {
  sensor_msgs::Imu imu;
  imu.header = header();
  expect_exact(imu);
  geometry_msgs::TwistWithCovarianceStamped twist_cov;
  twist_cov.header = header();
  expect_exact(twist_cov);
  geometry_msgs::TwistStamped twist;
  twist.header = header();
  expect_exact(twist);
  geometry_msgs::PoseStamped pose;
  pose.header = header();
  expect_exact(pose);
  nav_msgs::Odometry odometry;
  odometry.header = header();
  odometry.child_frame_id = "imu";
  expect_exact(odometry);
  expect_exact(cloud());
  sensor_msgs::Image image;
  image.header = header();
  image.height = 2;
  image.width = 3;
  image.encoding = "mono8";
  image.step = 3;
  image.data.assign(6, 9);
  expect_exact(image);
  sensor_msgs::CompressedImage compressed;
  compressed.header = header();
  compressed.format = "png";
  compressed.data.assign(40, 1);
  expect_exact(compressed);
  tf2_msgs::TFMessage tf;
  for (const char* child : {"lidar", "camera_optical"}) {
    geometry_msgs::TransformStamped t;
    t.header = header();
    t.child_frame_id = child;
    t.transform.rotation.w = 1;
    tf.transforms.push_back(t);
  }
  expect_exact(tf);
}

// fuzz_bag's input: a PointCloud2 whose `data` declared 4 GiB, which roscpp allocated.
TEST(Ros1MessageCheck, ADataLengthBeyondTheMessageIsNamed) {
  std::vector<uint8_t> bytes = serialize(cloud());
  const size_t data_count = bytes.size() - 1 - 32 - 4;  // before data (32 bytes) and is_dense
  uint32_t declared;
  std::memcpy(&declared, bytes.data() + data_count, 4);
  ASSERT_EQ(declared, 32u);
  const uint32_t huge = 0xffffffffu;
  std::memcpy(bytes.data() + data_count, &huge, 4);
  try {
    check_ros1_message("sensor_msgs/PointCloud2", bytes.data(), bytes.size(),
                       "mission.bag: topic '/points' message 3");
    FAIL() << "accepted";
  } catch (const IoError& e) {
    EXPECT_STREQ(e.what(),
                 "mission.bag: topic '/points' message 3: data declares 4294967295 bytes; the "
                 "message has 33 left");
  }
}

}  // namespace
}  // namespace keel::io
