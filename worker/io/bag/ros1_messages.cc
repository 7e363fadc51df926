#include "worker/io/bag/ros1_messages.h"

#include "worker/io/bag/ros1_reader.h"

namespace keel::io::ros1 {

namespace {

// std_msgs/Header: uint32 seq, time stamp (uint32 sec, uint32 nsec), string frame_id.
// roscpp takes sec and nsec as they are (no normalisation), and so does Keel.
TimeNs header(Ros1Reader& r, std::string_view* frame_id = nullptr) {
  r.u32("header.seq");
  const uint32_t sec = r.u32("header.stamp.sec");
  const uint32_t nsec = r.u32("header.stamp.nsec");
  const std::string_view frame = r.string("header.frame_id");
  if (frame_id) *frame_id = frame;
  return static_cast<TimeNs>(sec) * 1000000000 + nsec;
}

Eigen::Vector3d vector3(Ros1Reader& r, const char* field) {
  const double x = r.f64(field);
  const double y = r.f64(field);
  const double z = r.f64(field);
  return {x, y, z};
}

Eigen::Quaterniond quaternion(Ros1Reader& r, const char* field) {
  const double x = r.f64(field);
  const double y = r.f64(field);
  const double z = r.f64(field);
  const double w = r.f64(field);
  return Eigen::Quaterniond(w, x, y, z);
}

}  // namespace

std::string_view md5_of(std::string_view datatype) {
  // From the message packages' generated headers (ros::message_traits::MD5Sum).
  static constexpr std::pair<std::string_view, std::string_view> kSums[] = {
      {"sensor_msgs/Imu", "6a62c6daae103f4ff57a132d6f95cec2"},
      {"sensor_msgs/NavSatFix", "2d3a8cd499b9b4a0249fb98fd05cfa48"},
      {"geometry_msgs/TwistWithCovarianceStamped", "8927a1a12fb2607ceea095b2dc440a96"},
      {"geometry_msgs/TwistStamped", "98d34b0043a2093cf9d9345ab6eef12e"},
      {"geometry_msgs/PoseStamped", "d3812c3cbc69362b77dc0b19b345f8f5"},
      {"nav_msgs/Odometry", "cd5e73d190d741a2f92e81eda573aca7"},
      {"sensor_msgs/PointCloud2", "1158d486dd51d683ce2f1be655c3c181"},
      {"sensor_msgs/Image", "060021388200f6f0f447d0fcd9c64743"},
      {"sensor_msgs/CompressedImage", "8f7a12909da2c9d3332d540a0977563f"},
      {"tf2_msgs/TFMessage", "94810edda583a504dfda3829e70d7eec"},
  };
  for (const auto& [type, md5] : kSums)
    if (type == datatype) return md5;
  return {};
}

Imu decode_imu(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  Imu m;
  m.stamp_ns = header(r);
  quaternion(r, "orientation");
  r.skip_f64("orientation_covariance", 9);
  m.angular_velocity = vector3(r, "angular_velocity");
  r.skip_f64("angular_velocity_covariance", 9);
  m.linear_acceleration = vector3(r, "linear_acceleration");
  r.skip_f64("linear_acceleration_covariance", 9);
  return m;
}

NavSatFix decode_nav_sat_fix(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  NavSatFix m;
  m.stamp_ns = header(r);
  m.status = static_cast<int8_t>(r.u8("status.status"));
  r.u16("status.service");
  m.latitude_deg = r.f64("latitude");
  m.longitude_deg = r.f64("longitude");
  m.altitude_m = r.f64("altitude");
  for (double& c : m.position_covariance) c = r.f64("position_covariance");
  m.position_covariance_type = r.u8("position_covariance_type");
  return m;
}

Twist decode_twist_stamped(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  Twist m;
  m.stamp_ns = header(r);
  m.linear = vector3(r, "twist.linear");
  vector3(r, "twist.angular");
  return m;
}

Twist decode_twist_with_covariance_stamped(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  Twist m;
  m.stamp_ns = header(r);
  m.linear = vector3(r, "twist.twist.linear");
  vector3(r, "twist.twist.angular");
  r.skip_f64("twist.covariance", 36);
  return m;
}

Pose decode_pose_stamped(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  Pose m;
  m.stamp_ns = header(r);
  m.position = vector3(r, "pose.position");
  m.orientation = quaternion(r, "pose.orientation");
  return m;
}

Pose decode_odometry(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  Pose m;
  m.stamp_ns = header(r);
  r.string("child_frame_id");
  m.position = vector3(r, "pose.pose.position");
  m.orientation = quaternion(r, "pose.pose.orientation");
  r.skip_f64("pose.covariance", 36);
  vector3(r, "twist.twist.linear");
  vector3(r, "twist.twist.angular");
  r.skip_f64("twist.covariance", 36);
  return m;
}

std::vector<Transform> decode_tf_message(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  // Each TransformStamped holds at least 12 + 4 (header) + 4 (child_frame_id) + 7 * 8 bytes.
  const uint32_t count = r.sequence("transforms", 76);
  std::vector<Transform> out;
  out.reserve(count);
  for (uint32_t i = 0; i < count; ++i) {
    Transform t;
    std::string_view parent;
    header(r, &parent);
    t.parent_frame = std::string(parent);
    t.child_frame = std::string(r.string("transforms.child_frame_id"));
    t.translation = vector3(r, "transforms.transform.translation");
    t.rotation = quaternion(r, "transforms.transform.rotation");
    out.push_back(std::move(t));
  }
  return out;
}

PointCloud2 decode_point_cloud2(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  PointCloud2 m;
  m.stamp_ns = header(r);
  PointCloud2View& v = m.view;
  v.height = r.u32("height");
  v.width = r.u32("width");
  // A PointField: name (uint32 length + bytes), uint32 offset, uint8 datatype, uint32 count.
  const uint32_t fields = r.sequence("fields", 4 + 9);
  v.fields.reserve(fields);
  for (uint32_t i = 0; i < fields; ++i) {
    RosPointField f;
    f.name = r.string("fields.name");
    f.offset = r.u32("fields.offset");
    f.datatype = r.u8("fields.datatype");
    f.count = r.u32("fields.count");
    v.fields.push_back(f);
  }
  v.is_bigendian = r.boolean("is_bigendian");
  v.point_step = r.u32("point_step");
  v.row_step = r.u32("row_step");
  const std::string_view bytes = r.bytes("data");
  v.data = reinterpret_cast<const uint8_t*>(bytes.data());
  v.data_size = bytes.size();
  r.boolean("is_dense");
  return m;
}

Image decode_image(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  Image m;
  m.stamp_ns = header(r);
  ImageView& v = m.view;
  v.height = r.u32("height");
  v.width = r.u32("width");
  v.encoding = r.string("encoding");
  r.u8("is_bigendian");
  v.step = r.u32("step");
  const std::string_view bytes = r.bytes("data");
  v.data = reinterpret_cast<const uint8_t*>(bytes.data());
  v.data_size = bytes.size();
  return m;
}

CompressedImage decode_compressed_image(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  CompressedImage m;
  m.stamp_ns = header(r);
  m.format = r.string("format");
  const std::string_view bytes = r.bytes("data");
  m.data = reinterpret_cast<const uint8_t*>(bytes.data());
  m.size = bytes.size();
  return m;
}

}  // namespace keel::io::ros1
