// The Water Linked DVL A50's ROS messages, decoded from their bytes with every length checked:
//  - ROS1 `waterlinked_a50_ros_driver/DVL` (github.com/waterlinked/dvl-a50-ros-driver,
//    msg/DVL.msg, msg/DVLBeam.msg): Header header, float64 time, geometry_msgs/Vector3
//    velocity, float64 fom, float64 altitude, DVLBeam[] beams, bool velocity_valid,
//    int64 status, string form; DVLBeam = int64 id, float64 velocity, distance, rssi, nsd,
//    bool valid. ROS1 serialization (wiki.ros.org/msg): little endian, packed, arrays and
//    strings as a uint32 count then their elements.
//  - ROS 2 `dvl_msgs/msg/DVL` (the dvl_msgs package of the A50's ROS 2 driver,
//    github.com/paagutie/dvl-a50): as above with float64[9] covariance after fom; fields after
//    status (time_of_validity, time_of_transmission, form in newer versions) are not read.
//    CDR as in cdr_reader.h.
// Errors are BagFormatError naming the field, without the bag, topic or message (the reader
// adds them).
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/time.h"

namespace keel::io {

struct A50Beam {
  int64_t id = 0;           // transducer id, 0-3
  double velocity_m_s = 0;  // the DVL's velocity along this beam
  double distance_m = 0;    // range to the bottom along the beam
  double rssi_dbm = 0, nsd_dbm = 0;
  bool valid = false;  // bottom lock
};

struct A50Dvl {
  TimeNs stamp_ns = 0;                                     // header stamp; 0 when unset
  double time_ms = 0;                                      // since the previous velocity report
  Eigen::Vector3d velocity_m_s = Eigen::Vector3d::Zero();  // DVL frame (x fwd, y right, z down)
  double fom_m_s = 0;           // figure of merit: the velocity's expected error (std), m/s
  bool has_covariance = false;  // ROS 2 only
  std::array<double, 9> covariance_m2_s2 = {};  // row-major, xyz
  double altitude_m = 0;
  std::vector<A50Beam> beams;
  bool velocity_valid = false;
  int64_t status = 0;  // 0 normal, 1 operational issue (e.g. high temperature)
};

A50Dvl decode_a50_ros1(const uint8_t* data, size_t size);
A50Dvl decode_a50_ros2(const uint8_t* data, size_t size);

}  // namespace keel::io
