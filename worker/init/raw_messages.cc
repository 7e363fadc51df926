#include "worker/init/raw_messages.h"

#include <cstring>
#include <stdexcept>

#include "worker/io/bag/cdr_reader.h"
#include "worker/io/io_error.h"

namespace keel::init {

namespace {

// One field after another in either serialization. ROS1 (wiki.ros.org/msg): little endian,
// packed, strings and arrays as a uint32 count then the elements; CDR: cdr_reader.h.
class Cursor {
 public:
  explicit Cursor(const io::BagRawMessage& m) : m_(m) {
    if (m.cdr) cdr_.emplace(m.data, m.size);
  }

  uint8_t u8(const char* f) { return cdr_ ? cdr_->u8(f) : plain<uint8_t>(f); }
  uint16_t u16(const char* f) { return cdr_ ? cdr_->u16(f) : plain<uint16_t>(f); }
  uint32_t u32(const char* f) { return cdr_ ? cdr_->u32(f) : plain<uint32_t>(f); }
  double f64(const char* f) { return cdr_ ? cdr_->f64(f) : plain<double>(f); }
  std::string_view string(const char* f) {
    if (cdr_) return cdr_->string(f);
    const uint32_t n = u32(f);
    need(n, f);
    const std::string_view s(reinterpret_cast<const char*>(m_.data + pos_), n);
    pos_ += n;
    return s;
  }
  std::string_view bytes(const char* f) {
    if (cdr_) return cdr_->bytes(f);
    return string(f);
  }
  // A sequence's count (ROS1: checked against one byte per element).
  uint32_t sequence(const char* f, size_t min_bytes) {
    if (cdr_) return cdr_->sequence(f, min_bytes);
    const uint32_t n = u32(f);
    need(static_cast<uint64_t>(n) * min_bytes, f);
    return n;
  }
  void skip_bytes(size_t n, const char* f) {
    if (cdr_) {
      for (size_t i = 0; i < n; ++i) cdr_->u8(f);
      return;
    }
    need(n, f);
    pos_ += n;
  }
  Header header() {
    Header h;
    if (!cdr_) u32("header.seq");
    const uint32_t sec = u32("header.stamp.sec");
    const uint32_t nsec = u32("header.stamp.nsec");
    // ROS1 time is uint32 seconds, ROS 2 int32: both fit int64 ns.
    h.stamp_ns =
        (cdr_ ? static_cast<int64_t>(static_cast<int32_t>(sec)) : int64_t{sec}) * 1000000000 + nsec;
    h.frame_id = std::string(string("header.frame_id"));
    return h;
  }

 private:
  template <typename T>
  T plain(const char* f) {
    need(sizeof(T), f);
    T v;
    std::memcpy(&v, m_.data + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  void need(uint64_t n, const char* f) const {
    if (n > m_.size - pos_)
      throw io::IoError("field '" + std::string(f) + "': " + std::to_string(n) +
                        " bytes at offset " + std::to_string(pos_) + " run past the end of the " +
                        std::to_string(m_.size) + "-byte message");
  }

  const io::BagRawMessage& m_;
  std::optional<io::CdrReader> cdr_;
  size_t pos_ = 0;
};

// Runs `read` and names the message in any error it throws.
template <typename Read>
auto guarded(const std::string& what, Read&& read) {
  try {
    return read();
  } catch (const std::exception& e) {
    throw io::IoError(what + ": " + e.what());
  }
}

io::FieldType field_type(uint8_t datatype, std::string_view name, const std::string& what) {
  // sensor_msgs/PointField: INT8 1, UINT8 2, INT16 3, UINT16 4, INT32 5, UINT32 6, FLOAT32 7,
  // FLOAT64 8.
  static const io::FieldType kTypes[] = {io::FieldType::kInt8,    io::FieldType::kUint8,
                                         io::FieldType::kInt16,   io::FieldType::kUint16,
                                         io::FieldType::kInt32,   io::FieldType::kUint32,
                                         io::FieldType::kFloat32, io::FieldType::kFloat64};
  if (datatype < 1 || datatype > 8)
    throw io::IoError(what + ": field '" + std::string(name) + "' has datatype " +
                      std::to_string(datatype) + "; expected 1..8 (sensor_msgs/PointField)");
  return kTypes[datatype - 1];
}

}  // namespace

std::string plain_type(std::string_view datatype) {
  std::string s(datatype);
  const size_t at = s.find("/msg/");
  if (at != std::string::npos) s.erase(at, 4);
  return s;
}

bool has_header(std::string_view datatype) {
  const std::string t = plain_type(datatype);
  static const char* kTypes[] = {"sensor_msgs/Imu",
                                 "sensor_msgs/PointCloud2",
                                 "sensor_msgs/Image",
                                 "sensor_msgs/CompressedImage",
                                 "sensor_msgs/NavSatFix",
                                 "sensor_msgs/FluidPressure",
                                 "sensor_msgs/CameraInfo",
                                 "sensor_msgs/LaserScan",
                                 "nav_msgs/Odometry",
                                 "velodyne_msgs/VelodyneScan",
                                 "waterlinked_a50_ros_driver/DVL",
                                 "dvl_msgs/DVL"};
  for (const char* k : kTypes)
    if (t == k) return true;
  return t.size() > 7 && t.compare(t.size() - 7, 7, "Stamped") == 0;
}

Header read_header(const io::BagRawMessage& m, const std::string& what) {
  return guarded(what, [&] { return Cursor(m).header(); });
}

CloudFields read_point_cloud2(const io::BagRawMessage& m, const std::string& what) {
  return guarded(what, [&] {
    Cursor c(m);
    c.header();
    const uint32_t height = c.u32("height");
    const uint32_t width = c.u32("width");
    CloudFields out;
    const uint32_t n = c.sequence("fields", 13);
    std::vector<io::PackedField> fields;
    for (uint32_t i = 0; i < n; ++i) {
      io::PackedField f;
      f.name = std::string(c.string("fields.name"));
      f.offset = c.u32("fields.offset");
      f.type = field_type(c.u8("fields.datatype"), f.name, what);
      f.count = std::max<uint32_t>(1, c.u32("fields.count"));
      fields.push_back(f);
    }
    if (c.u8("is_bigendian")) throw io::IoError("big-endian point data is not supported");
    const uint32_t point_step = c.u32("point_step");
    const uint32_t row_step = c.u32("row_step");
    const std::string_view data = c.bytes("data");
    const uint64_t row_bytes = static_cast<uint64_t>(width) * point_step;
    if (row_step < row_bytes || data.size() < static_cast<uint64_t>(row_step) * height)
      throw io::IoError("data holds " + std::to_string(data.size()) + " bytes, less than " +
                        std::to_string(height) + " rows of " + std::to_string(row_step));
    for (const auto& f : fields)
      if (f.offset + io::field_size(f.type) > point_step)
        throw io::IoError("field '" + f.name + "' lies outside the point record");
    out.num_points = static_cast<size_t>(width) * height;
    out.view.num_points = out.num_points;
    out.view.point_step = point_step;
    out.view.fields = std::move(fields);
    const auto* bytes = reinterpret_cast<const uint8_t*>(data.data());
    if (row_step == row_bytes || height <= 1) {
      out.view.data = bytes;
    } else {
      out.unpadded.resize(out.num_points * point_step);
      for (size_t r = 0; r < height; ++r)
        std::memcpy(out.unpadded.data() + r * row_bytes, bytes + r * row_step, row_bytes);
      out.view.data = out.unpadded.data();
    }
    return out;
  });
}

ImageInfo read_image_info(const io::BagRawMessage& m, const std::string& what) {
  return guarded(what, [&] {
    Cursor c(m);
    c.header();
    ImageInfo info;
    if (plain_type(m.type) == "sensor_msgs/CompressedImage") {
      info.encoding = std::string(c.string("format"));
      return info;
    }
    info.height = c.u32("height");
    info.width = c.u32("width");
    info.encoding = std::string(c.string("encoding"));
    return info;
  });
}

std::string read_odometry_child_frame(const io::BagRawMessage& m, const std::string& what) {
  return guarded(what, [&] {
    Cursor c(m);
    c.header();
    return std::string(c.string("child_frame_id"));
  });
}

Fix read_nav_sat_fix(const io::BagRawMessage& m, const std::string& what) {
  return guarded(what, [&] {
    Cursor c(m);
    c.header();
    Fix f;
    f.status = static_cast<int8_t>(c.u8("status.status"));
    c.u16("status.service");
    f.latitude_deg = c.f64("latitude");
    f.longitude_deg = c.f64("longitude");
    f.altitude_m = c.f64("altitude");
    return f;
  });
}

std::optional<VelodyneFactory> read_velodyne_factory(const io::BagRawMessage& m,
                                                     const std::string& what) {
  return guarded(what, [&]() -> std::optional<VelodyneFactory> {
    Cursor c(m);
    c.header();
    // VelodynePacket: time stamp (8 bytes), uint8[1206] data (fixed size: no count).
    const uint32_t packets = c.sequence("packets", 1214);
    if (packets == 0) return std::nullopt;
    c.u32("packets.stamp.sec");
    c.u32("packets.stamp.nsec");
    c.skip_bytes(1204, "packets.data");
    VelodyneFactory f;
    f.return_mode = c.u8("packets.data[1204]");
    f.product = c.u8("packets.data[1205]");
    f.packets = packets;
    return f;
  });
}

std::string velodyne_model(uint8_t product) {
  switch (product) {
    case 0x21:
      return "HDL32E";
    case 0x22:
      return "VLP16";
    case 0x28:
      return "VLP32C";
    default:
      return "";
  }
}

std::string velodyne_product_name(uint8_t product) {
  switch (product) {
    case 0x21:
      return "HDL-32E";
    case 0x22:
      return "VLP-16";
    case 0x24:
      return "Puck Hi-Res";
    case 0x28:
      return "VLP-32C";
    case 0x31:
      return "Velarray";
    case 0xA1:
      return "VLS-128";
    default: {
      char buffer[32];
      std::snprintf(buffer, sizeof(buffer), "unknown product 0x%02X", product);
      return buffer;
    }
  }
}

}  // namespace keel::init
