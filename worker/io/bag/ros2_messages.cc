#include "worker/io/bag/ros2_messages.h"

#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/cdr_reader.h"

namespace keel::io::ros2 {

namespace {

// std_msgs/msg/Header: builtin_interfaces/msg/Time stamp (int32 sec, uint32 nanosec),
// string frame_id.
TimeNs header(CdrReader& cdr, std::string_view* frame_id = nullptr) {
  const int32_t sec = cdr.i32("header.stamp.sec");
  const uint32_t nanosec = cdr.u32("header.stamp.nanosec");
  if (nanosec >= 1000000000u)
    throw BagFormatError("CDR: field 'header.stamp.nanosec' is " + std::to_string(nanosec) +
                         ", expected below 1e9");
  const std::string_view frame = cdr.string("header.frame_id");
  if (frame_id) *frame_id = frame;
  return static_cast<TimeNs>(sec) * 1000000000 + nanosec;
}

Eigen::Vector3d vector3(CdrReader& cdr, const char* field) {
  const double x = cdr.f64(field);
  const double y = cdr.f64(field);
  const double z = cdr.f64(field);
  return {x, y, z};
}

Eigen::Quaterniond quaternion(CdrReader& cdr, const char* field) {
  const double x = cdr.f64(field);
  const double y = cdr.f64(field);
  const double z = cdr.f64(field);
  const double w = cdr.f64(field);
  return Eigen::Quaterniond(w, x, y, z);
}

}  // namespace

Imu decode_imu(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  Imu m;
  m.stamp_ns = header(cdr);
  quaternion(cdr, "orientation");
  cdr.skip_f64("orientation_covariance", 9);
  m.angular_velocity = vector3(cdr, "angular_velocity");
  cdr.skip_f64("angular_velocity_covariance", 9);
  m.linear_acceleration = vector3(cdr, "linear_acceleration");
  cdr.skip_f64("linear_acceleration_covariance", 9);
  return m;
}

NavSatFix decode_nav_sat_fix(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  NavSatFix m;
  m.stamp_ns = header(cdr);
  m.status = static_cast<int8_t>(cdr.u8("status.status"));
  cdr.u16("status.service");
  m.latitude_deg = cdr.f64("latitude");
  m.longitude_deg = cdr.f64("longitude");
  m.altitude_m = cdr.f64("altitude");
  for (double& c : m.position_covariance) c = cdr.f64("position_covariance");
  m.position_covariance_type = cdr.u8("position_covariance_type");
  return m;
}

Twist decode_twist_stamped(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  Twist m;
  m.stamp_ns = header(cdr);
  m.linear = vector3(cdr, "twist.linear");
  vector3(cdr, "twist.angular");
  return m;
}

Twist decode_twist_with_covariance_stamped(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  Twist m;
  m.stamp_ns = header(cdr);
  m.linear = vector3(cdr, "twist.twist.linear");
  vector3(cdr, "twist.twist.angular");
  cdr.skip_f64("twist.covariance", 36);
  return m;
}

Pose decode_pose_stamped(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  Pose m;
  m.stamp_ns = header(cdr);
  m.position = vector3(cdr, "pose.position");
  m.orientation = quaternion(cdr, "pose.orientation");
  return m;
}

Pose decode_odometry(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  Pose m;
  m.stamp_ns = header(cdr);
  cdr.string("child_frame_id");
  m.position = vector3(cdr, "pose.pose.position");
  m.orientation = quaternion(cdr, "pose.pose.orientation");
  cdr.skip_f64("pose.covariance", 36);
  vector3(cdr, "twist.twist.linear");
  vector3(cdr, "twist.twist.angular");
  cdr.skip_f64("twist.covariance", 36);
  return m;
}

std::vector<Transform> decode_tf_message(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  // Each TransformStamped holds at least 4 + 4 + 4 (header) + 4 (child) + 7 * 8 bytes.
  const uint32_t count = cdr.sequence("transforms", 72);
  std::vector<Transform> out;
  out.reserve(count);
  for (uint32_t i = 0; i < count; ++i) {
    Transform t;
    std::string_view parent;
    header(cdr, &parent);
    t.parent_frame = std::string(parent);
    t.child_frame = std::string(cdr.string("transforms.child_frame_id"));
    t.translation = vector3(cdr, "transforms.transform.translation");
    t.rotation = quaternion(cdr, "transforms.transform.rotation");
    out.push_back(std::move(t));
  }
  return out;
}

PointCloud2 decode_point_cloud2(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  PointCloud2 m;
  m.stamp_ns = header(cdr);
  PointCloud2View& v = m.view;
  v.height = cdr.u32("height");
  v.width = cdr.u32("width");
  // A PointField holds at least 4 (name length) + 4 + 1 + 4 bytes (with alignment: 16).
  const uint32_t fields = cdr.sequence("fields", 13);
  v.fields.reserve(fields);
  for (uint32_t i = 0; i < fields; ++i) {
    RosPointField f;
    f.name = cdr.string("fields.name");
    f.offset = cdr.u32("fields.offset");
    f.datatype = cdr.u8("fields.datatype");
    f.count = cdr.u32("fields.count");
    v.fields.push_back(f);
  }
  v.is_bigendian = cdr.boolean("is_bigendian");
  v.point_step = cdr.u32("point_step");
  v.row_step = cdr.u32("row_step");
  const std::string_view bytes = cdr.bytes("data");
  v.data = reinterpret_cast<const uint8_t*>(bytes.data());
  v.data_size = bytes.size();
  cdr.boolean("is_dense");
  return m;
}

Image decode_image(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  Image m;
  m.stamp_ns = header(cdr);
  ImageView& v = m.view;
  v.height = cdr.u32("height");
  v.width = cdr.u32("width");
  v.encoding = cdr.string("encoding");
  cdr.u8("is_bigendian");
  v.step = cdr.u32("step");
  const std::string_view bytes = cdr.bytes("data");
  v.data = reinterpret_cast<const uint8_t*>(bytes.data());
  v.data_size = bytes.size();
  return m;
}

CompressedImage decode_compressed_image(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  CompressedImage m;
  m.stamp_ns = header(cdr);
  m.format = cdr.string("format");
  const std::string_view bytes = cdr.bytes("data");
  m.data = reinterpret_cast<const uint8_t*>(bytes.data());
  m.size = bytes.size();
  return m;
}

}  // namespace keel::io::ros2
