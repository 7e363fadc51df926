#include "worker/io/bag/ros1_message_check.h"

#include "worker/io/io_error.h"

namespace keel::io {
namespace {

// Walks a message's fields; each step checks its bytes are there.
class Walker {
 public:
  Walker(const uint8_t* data, size_t size, const std::string& what)
      : data_(data), size_(size), what_(what) {}

  void fixed(size_t bytes, const char* field) { take(bytes, field); }
  uint32_t count(const char* field) {
    take(4, field);
    const uint8_t* p = data_ + at_ - 4;
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
  }
  // A string, or an array of `element_size`-byte elements.
  void array(size_t element_size, const char* field) {
    const uint64_t bytes = uint64_t(count(field)) * element_size;
    take(bytes, field);
  }
  // The count of an array of variable-size elements of at least `min_element_size` bytes.
  uint32_t elements(size_t min_element_size, const char* field) {
    const uint32_t n = count(field);
    if (uint64_t(n) * min_element_size > size_ - at_)
      overrun(uint64_t(n) * min_element_size, field);
    return n;
  }
  void header() {
    fixed(12, "header");  // seq, stamp
    array(1, "header.frame_id");
  }

 private:
  void take(uint64_t bytes, const char* field) {
    if (bytes > size_ - at_) overrun(bytes, field);
    at_ += static_cast<size_t>(bytes);
  }
  [[noreturn]] void overrun(uint64_t bytes, const char* field) const {
    throw IoError(what_ + ": " + field + " declares " + std::to_string(bytes) +
                  " bytes; the message has " + std::to_string(size_ - at_) + " left");
  }

  const uint8_t* data_;
  size_t size_;
  size_t at_ = 0;
  const std::string& what_;
};

constexpr size_t kDouble = 8;

}  // namespace

void check_ros1_message(std::string_view datatype, const uint8_t* data, size_t size,
                        const std::string& what) {
  Walker w(data, size, what);
  if (datatype == "sensor_msgs/Imu") {
    w.header();
    w.fixed((4 + 9 + 3 + 9 + 3 + 9) * kDouble, "orientation .. linear_acceleration_covariance");
  } else if (datatype == "sensor_msgs/NavSatFix") {
    w.header();
    w.fixed(1 + 2, "status");  // int8 status, uint16 service
    w.fixed((3 + 9) * kDouble + 1, "latitude .. position_covariance_type");
  } else if (datatype == "geometry_msgs/TwistWithCovarianceStamped") {
    w.header();
    w.fixed((6 + 36) * kDouble, "twist");
  } else if (datatype == "geometry_msgs/TwistStamped") {
    w.header();
    w.fixed(6 * kDouble, "twist");
  } else if (datatype == "geometry_msgs/PoseStamped") {
    w.header();
    w.fixed(7 * kDouble, "pose");
  } else if (datatype == "nav_msgs/Odometry") {
    w.header();
    w.array(1, "child_frame_id");
    w.fixed((7 + 36 + 6 + 36) * kDouble, "pose and twist");
  } else if (datatype == "sensor_msgs/PointCloud2") {
    w.header();
    w.fixed(8, "height, width");
    const uint32_t fields =
        w.elements(4 + 9, "fields");  // name (a string), offset, datatype, count
    for (uint32_t i = 0; i < fields; ++i) {
      w.array(1, "fields[].name");
      w.fixed(9, "fields[]");
    }
    w.fixed(9, "is_bigendian, point_step, row_step");
    w.array(1, "data");
    w.fixed(1, "is_dense");
  } else if (datatype == "sensor_msgs/Image") {
    w.header();
    w.fixed(8, "height, width");
    w.array(1, "encoding");
    w.fixed(5, "is_bigendian, step");
    w.array(1, "data");
  } else if (datatype == "sensor_msgs/CompressedImage") {
    w.header();
    w.array(1, "format");
    w.array(1, "data");
  } else if (datatype == "tf2_msgs/TFMessage") {
    const uint32_t transforms = w.elements(12 + 4 + 4 + 7 * kDouble, "transforms");
    for (uint32_t i = 0; i < transforms; ++i) {
      w.header();
      w.array(1, "transforms[].child_frame_id");
      w.fixed(7 * kDouble, "transforms[].transform");
    }
  }
}

}  // namespace keel::io
