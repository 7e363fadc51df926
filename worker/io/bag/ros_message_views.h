// The contents of sensor_msgs PointCloud2 and Image without their header, as views into a
// decoded message (ROS1) or into its CDR bytes (ROS 2): what both bag readers hand to
// unpack_point_cloud2 and unpack_image (ros_messages.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

namespace keel::io {

struct RosPointField {
  std::string_view name;
  uint32_t offset = 0;
  uint8_t datatype = 0;  // sensor_msgs/PointField: INT8 = 1 ... FLOAT64 = 8
  uint32_t count = 1;
};

// sensor_msgs/PointCloud2 without its header.
struct PointCloud2View {
  uint32_t height = 0, width = 0;
  std::vector<RosPointField> fields;
  bool is_bigendian = false;
  uint32_t point_step = 0, row_step = 0;
  const uint8_t* data = nullptr;
  size_t data_size = 0;
};

// sensor_msgs/Image without its header.
struct ImageView {
  uint32_t height = 0, width = 0;
  std::string_view encoding;
  uint32_t step = 0;
  const uint8_t* data = nullptr;
  size_t data_size = 0;
};

}  // namespace keel::io
