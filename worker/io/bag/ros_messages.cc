#include "worker/io/bag/ros_messages.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "worker/io/io_error.h"
#include "worker/io/lidar/velodyne_scan.h"

namespace keel::io {

namespace {

FieldType field_type(uint8_t datatype, std::string_view name, const std::string& what) {
  switch (datatype) {  // sensor_msgs/PointField constants
    case 1:
      return FieldType::kInt8;
    case 2:
      return FieldType::kUint8;
    case 3:
      return FieldType::kInt16;
    case 4:
      return FieldType::kUint16;
    case 5:
      return FieldType::kInt32;
    case 6:
      return FieldType::kUint32;
    case 7:
      return FieldType::kFloat32;
    case 8:
      return FieldType::kFloat64;
  }
  throw IoError(what + ": field '" + std::string(name) + "' has unknown datatype " +
                std::to_string(datatype));
}

}  // namespace

PointCloud unpack_point_cloud2(const PointCloud2View& msg, TimeNs t_ns,
                               const ScanReadOptions& options, const std::string& what) {
  if (msg.is_bigendian) throw IoError(what + ": big-endian point data is not supported");
  // 64-bit products: width * point_step and row_step * height cannot overflow from 32-bit
  // factors, so a hostile size is caught by the comparison, not wrapped past it.
  const uint64_t points = static_cast<uint64_t>(msg.width) * msg.height;
  const uint64_t row_bytes = static_cast<uint64_t>(msg.width) * msg.point_step;
  if (msg.row_step < row_bytes || msg.data_size < static_cast<uint64_t>(msg.row_step) * msg.height)
    throw IoError(what + ": data holds " + std::to_string(msg.data_size) + " bytes; " +
                  std::to_string(msg.height) + " rows of " + std::to_string(msg.row_step) +
                  " bytes (width " + std::to_string(msg.width) + " x point_step " +
                  std::to_string(msg.point_step) + ") needed");
  PackedCloudView view;
  view.num_points = points;
  view.point_step = msg.point_step;
  for (const auto& f : msg.fields) {
    const FieldType type = field_type(f.datatype, f.name, what);
    if (static_cast<uint64_t>(f.offset) + field_size(type) > msg.point_step)
      throw IoError(what + ": field '" + std::string(f.name) + "' lies outside the " +
                    std::to_string(msg.point_step) + "-byte point record");
    view.fields.push_back({std::string(f.name), type, f.offset, std::max<size_t>(1, f.count)});
  }
  if (msg.row_step == row_bytes || msg.height <= 1) {
    view.data = msg.data;
    return unpack_cloud(view, t_ns, options, what);
  }
  std::vector<uint8_t> packed(points * msg.point_step);  // drop row padding
  for (size_t r = 0; r < msg.height; ++r)
    std::memcpy(packed.data() + r * row_bytes, msg.data + r * msg.row_step, row_bytes);
  view.data = packed.data();
  return unpack_cloud(view, t_ns, options, what);
}

ImageFrame unpack_image(const ImageView& msg, bool decode, const std::string& what) {
  ImageFrame frame;
  frame.width = static_cast<int>(msg.width);
  frame.height = static_cast<int>(msg.height);
  int in_channels = 0;
  const std::string_view e = msg.encoding;
  if (e == "mono8" || e == "8UC1")
    frame.channels = in_channels = 1, frame.bit_depth = 8;
  else if (e == "mono16" || e == "16UC1")
    frame.channels = in_channels = 1, frame.bit_depth = 16;
  else if (e == "rgb8" || e == "bgr8" || e == "8UC3")
    frame.channels = 3, in_channels = 3, frame.bit_depth = 8;
  else if (e == "rgba8" || e == "bgra8" || e == "8UC4")
    frame.channels = 3, in_channels = 4, frame.bit_depth = 8;
  else
    throw IoError(what + ": image encoding '" + std::string(e) +
                  "' not supported (mono8, mono16, rgb8, bgr8, rgba8, bgra8)");
  if (msg.width > (1u << 16) || msg.height > (1u << 16))
    throw IoError(what + ": image of " + std::to_string(msg.width) + "x" +
                  std::to_string(msg.height) + " pixels exceeds 65536 on a side");
  const size_t pixel_bytes = in_channels * frame.bit_depth / 8;
  if (msg.step < msg.width * pixel_bytes ||
      msg.data_size < static_cast<uint64_t>(msg.step) * msg.height)
    throw IoError(what + ": image data holds " + std::to_string(msg.data_size) + " bytes; " +
                  std::to_string(msg.height) + " rows of " + std::to_string(msg.step) + " needed");
  if (!decode) return frame;
  const bool swap = e == "bgr8" || e == "bgra8";
  frame.pixels.resize(static_cast<size_t>(frame.width) * frame.height * frame.channels *
                      frame.bit_depth / 8);
  size_t out = 0;
  for (size_t r = 0; r < msg.height; ++r) {
    const uint8_t* row = msg.data + r * msg.step;
    if (in_channels == frame.channels && !swap) {
      std::memcpy(frame.pixels.data() + out, row, msg.width * pixel_bytes);
      out += msg.width * pixel_bytes;
      continue;
    }
    for (size_t c = 0; c < msg.width; ++c) {
      const uint8_t* p = row + c * in_channels;
      frame.pixels[out++] = swap ? p[2] : p[0];
      frame.pixels[out++] = p[1];
      frame.pixels[out++] = swap ? p[0] : p[2];
    }
  }
  return frame;
}

Eigen::Vector3d finite_vector(double x, double y, double z, const std::string& what) {
  const Eigen::Vector3d out(x, y, z);
  if (!out.allFinite()) throw IoError(what + ": non-finite value");
  return out;
}

Pose3 checked_pose(const Eigen::Quaterniond& q, const Eigen::Vector3d& position,
                   const std::string& what) {
  if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-3)
    throw IoError(
        what + ": orientation is not a unit quaternion (|q| = " + std::to_string(q.norm()) + ")");
  if (!position.allFinite()) throw IoError(what + ": non-finite value");
  return make_pose(q, position);
}

void check_increasing(const std::string& what, size_t index, TimeNs t_ns, TimeNs previous_ns) {
  if (index > 0 && t_ns <= previous_ns)
    throw IoError(what + ": " + (t_ns == previous_ns ? "duplicate" : "decreasing") + " stamp " +
                  format_seconds(t_ns) + " (previous " + format_seconds(previous_ns) +
                  "); expected strictly increasing header stamps");
}

void check_packet_options(const std::string& bag, const std::string& topic, bool is_packets,
                          const ScanReadOptions& options) {
  if (is_packets && !options.packets)
    throw IoError(bag + ": topic '" + topic +
                  "' holds raw Velodyne packets (velodyne_msgs/VelodyneScan): give its lidar "
                  "sensor `packets: {model: VLP16 | VLP32C | HDL32E}` in mission.yaml");
  if (!is_packets && options.packets)
    throw IoError(bag + ": topic '" + topic +
                  "' holds point clouds, not velodyne_msgs/VelodyneScan packets: remove the "
                  "sensor's `packets:`");
}

PointCloud decode_velodyne_message(const uint8_t* data, size_t size, bool cdr, TimeNs received_ns,
                                   const ScanReadOptions& options, const std::string& what,
                                   std::vector<lidar::VelodynePoint>& scratch) {
  lidar::VelodyneScanView scan;
  try {
    scan = cdr ? lidar::parse_velodyne_scan_cdr(data, size)
               : lidar::parse_velodyne_scan_ros1(data, size);
  } catch (const IoError& e) {
    throw IoError(what + ": " + e.what());
  }
  // The firing times are the point times: point_time (a PointCloud2 field) does not apply.
  PointCloud cloud =
      lidar::decode_velodyne_scan(scan, received_ns, *options.packets, {}, what, scratch);
  cloud.frame = options.frame;
  return cloud;
}

}  // namespace keel::io
