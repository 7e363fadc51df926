// A velodyne_msgs/VelodyneScan message (ROS 1 velodyne_msgs/VelodyneScan, ROS 2
// velodyne_msgs/msg/VelodyneScan: std_msgs/Header header, VelodynePacket[] packets, each
// {time stamp, uint8[1206] data}) as views into its serialised bytes, and its decoding into
// one scan with every point's firing time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "core/time.h"
#include "worker/io/lidar/velodyne_packet.h"

namespace keel::io::lidar {

struct VelodynePacketView {
  TimeNs stamp_ns = 0;
  const uint8_t* data = nullptr;  // kVelodynePacketBytes
};

struct VelodyneScanView {
  TimeNs stamp_ns = 0;  // header stamp
  std::vector<VelodynePacketView> packets;
};

// ROS 1 serialisation (uint32 seq, time, string frame_id, uint32 count, then per packet a
// time and 1206 bytes). Throws IoError naming the field that runs past the end.
VelodyneScanView parse_velodyne_scan_ros1(const uint8_t* data, size_t size);
// CDR (plain XCDR1/XCDR2, either endianness; a packet's stamp is 4-aligned, so packets are
// 1216 bytes apart). Throws IoError naming the field.
VelodyneScanView parse_velodyne_scan_cdr(const uint8_t* data, size_t size);

// One scan per message: t_ns is the first packet's stamp (its first firing); each point's
// time_s counts from there, from the packets' own microsecond clocks (exact, hour roll-over
// handled) plus the firing offset in the packet; when the packet clocks disagree with the
// packet stamps by more than 50 ms (clock not set, packets out of order) the stamps give the
// packet offsets instead. A packet without a stamp takes the header stamp, then
// `fallback_stamp_ns` (the bag's receive time). Errors (IoError) name `what` (topic and
// message) and the packet index.
PointCloud decode_velodyne_scan(const VelodyneScanView& scan, TimeNs fallback_stamp_ns,
                                const VelodyneCalibration& calibration,
                                const VelodyneDecodeOptions& options, const std::string& what,
                                std::vector<VelodynePoint>& scratch);

}  // namespace keel::io::lidar
