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
#include <vector>

// The A50 driver's message, serialized by hand (no message package of the driver is
// installed): rosbag writes it through these traits. MD5 by the genmsg rule over
// msg/DVL.msg and msg/DVLBeam.msg of github.com/waterlinked/dvl-a50-ros-driver.
namespace keel::sim {
struct A50Ros1Bytes {
  std::vector<uint8_t> bytes;
};
}  // namespace keel::sim

namespace ros {
namespace message_traits {
template <>
struct MD5Sum<keel::sim::A50Ros1Bytes> {
  static const char* value() { return "dea1debc1aca7804a62c507714ec3777"; }
  static const char* value(const keel::sim::A50Ros1Bytes&) { return value(); }
};
template <>
struct DataType<keel::sim::A50Ros1Bytes> {
  static const char* value() { return "waterlinked_a50_ros_driver/DVL"; }
  static const char* value(const keel::sim::A50Ros1Bytes&) { return value(); }
};
template <>
struct Definition<keel::sim::A50Ros1Bytes> {
  static const char* value() {
    return "Header header\nfloat64 time\ngeometry_msgs/Vector3 velocity\nfloat64 fom\n"
           "float64 altitude\nDVLBeam[] beams\nbool velocity_valid\nint64 status\nstring form\n"
           "\n================================================================================\n"
           "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n"
           "\n================================================================================\n"
           "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"
           "\n================================================================================\n"
           "MSG: waterlinked_a50_ros_driver/DVLBeam\nint64 id\nfloat64 velocity\n"
           "float64 distance\nfloat64 rssi\nfloat64 nsd\nbool valid\n";
  }
  static const char* value(const keel::sim::A50Ros1Bytes&) { return value(); }
};
}  // namespace message_traits
namespace serialization {
template <>
struct Serializer<keel::sim::A50Ros1Bytes> {
  template <typename Stream>
  static void write(Stream& stream, const keel::sim::A50Ros1Bytes& m) {
    std::memcpy(stream.advance(static_cast<uint32_t>(m.bytes.size())), m.bytes.data(),
                m.bytes.size());
  }
  template <typename Stream>
  static void read(Stream&, keel::sim::A50Ros1Bytes&) {}
  static uint32_t serializedLength(const keel::sim::A50Ros1Bytes& m) {
    return static_cast<uint32_t>(m.bytes.size());
  }
};
}  // namespace serialization
}  // namespace ros

namespace keel::sim {
namespace {

template <typename T>
void put(std::vector<uint8_t>& out, T v) {
  const size_t at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &v, sizeof(T));
}

void put_string(std::vector<uint8_t>& out, const std::string& s) {
  put(out, static_cast<uint32_t>(s.size()));
  out.insert(out.end(), s.begin(), s.end());
}

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

void BagWriter::a50_dvl(const std::string& topic, const std::string& frame, const io::A50Dvl& m) {
  A50Ros1Bytes msg;
  std::vector<uint8_t>& b = msg.bytes;
  const ros::Time stamp = to_ros(m.stamp_ns);
  put(b, uint32_t{0}), put(b, stamp.sec), put(b, stamp.nsec);  // header: seq, stamp
  put_string(b, frame);
  put(b, m.time_ms);
  for (int i = 0; i < 3; ++i) put(b, m.velocity_m_s(i));
  put(b, m.fom_m_s), put(b, m.altitude_m);
  put(b, static_cast<uint32_t>(m.beams.size()));
  for (const io::A50Beam& beam : m.beams) {
    put(b, beam.id);
    put(b, beam.velocity_m_s), put(b, beam.distance_m), put(b, beam.rssi_dbm), put(b, beam.nsd_dbm);
    put(b, static_cast<uint8_t>(beam.valid));
  }
  put(b, static_cast<uint8_t>(m.velocity_valid));
  put(b, m.status);
  put_string(b, "json_v3");
  impl_->bag.write(topic, stamp.isZero() ? ros::Time(1) : stamp, msg);
}

void BagWriter::close() {
  if (impl_ && impl_->bag.isOpen()) impl_->bag.close();
}

}  // namespace keel::sim
