// What `keel init` reads of a recorded message of any type, from its serialized bytes (ROS1
// serialization or CDR, bag_source.h's BagRawMessage): the std_msgs/Header (stamp, frame_id)
// of the types that start with one, and per type the few fields a mission draft needs:
// PointCloud2 fields, Image encoding and size, Odometry's child frame, NavSatFix's position,
// the factory byte of a velodyne_msgs/VelodyneScan's first packet. Layouts: the .msg files of
// ROS common_interfaces, velodyne_msgs (VelodynePacket: time stamp, uint8[1206] data). Every
// read is bounds-checked; a short message throws IoError naming `what` and the field.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.h"
#include "worker/io/bag/bag_source.h"
#include "worker/io/cloud/packed_cloud.h"

namespace keel::init {

// "sensor_msgs/msg/Imu" -> "sensor_msgs/Imu": ROS1 and ROS 2 names compared alike.
std::string plain_type(std::string_view datatype);

// Whether the type's first field is a std_msgs/Header (sensor messages, *Stamped, Odometry,
// VelodyneScan, the DVL drivers' messages).
bool has_header(std::string_view datatype);

struct Header {
  TimeNs stamp_ns = 0;
  std::string frame_id;
};
Header read_header(const io::BagRawMessage& m, const std::string& what);

// A PointCloud2's fields and records (a view into the message), little-endian records only.
struct CloudFields {
  size_t num_points = 0;
  io::PackedCloudView view;       // data points into the message; fields owned here
  std::vector<uint8_t> unpadded;  // rows copied together when row_step pads them
};
CloudFields read_point_cloud2(const io::BagRawMessage& m, const std::string& what);

struct ImageInfo {
  std::string encoding;            // Image: its encoding; CompressedImage: its format
  uint32_t width = 0, height = 0;  // 0 for a CompressedImage
};
ImageInfo read_image_info(const io::BagRawMessage& m, const std::string& what);

// nav_msgs/Odometry.child_frame_id.
std::string read_odometry_child_frame(const io::BagRawMessage& m, const std::string& what);

struct Fix {
  int status = -1;  // NavSatStatus: -1 no fix, 0 fix, 1 SBAS, 2 GBAS
  double latitude_deg = 0, longitude_deg = 0, altitude_m = 0;
};
Fix read_nav_sat_fix(const io::BagRawMessage& m, const std::string& what);

// The first packet's factory bytes (VLP-16 manual, "Factory Bytes": return mode 0x37
// strongest / 0x38 last / 0x39 dual; product 0x21 HDL-32E, 0x22 VLP-16, 0x24 Puck Hi-Res,
// 0x28 VLP-32C, 0xA1 VLS-128); nothing when the scan holds no packet.
struct VelodyneFactory {
  uint8_t return_mode = 0, product = 0;
  size_t packets = 0;  // in this message
};
std::optional<VelodyneFactory> read_velodyne_factory(const io::BagRawMessage& m,
                                                     const std::string& what);
// "VLP16", "VLP32C", "HDL32E" (what mission.yaml's packets.model knows), else "".
std::string velodyne_model(uint8_t product);
// A readable name of any product byte ("VLS-128", "unknown product 0x42").
std::string velodyne_product_name(uint8_t product);

}  // namespace keel::init
