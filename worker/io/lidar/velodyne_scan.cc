#include "worker/io/lidar/velodyne_scan.h"

#include <cmath>
#include <cstring>

#include "worker/io/io_error.h"

namespace keel::io::lidar {

namespace {

// Bounds-checked reads over one serialised message; `origin` is where CDR alignment counts
// from (after the encapsulation header), `swap` for big-endian CDR.
class Cursor {
 public:
  Cursor(const uint8_t* data, size_t size, size_t position, size_t origin, bool swap)
      : data_(data), size_(size), position_(position), origin_(origin), swap_(swap) {}

  void align(size_t n) {
    const size_t misalign = (position_ - origin_) % n;
    if (misalign) skip(n - misalign, "padding");
  }
  uint32_t u32(const char* field) {
    need(4, field);
    uint8_t b[4];
    std::memcpy(b, data_ + position_, 4);
    if (swap_) std::swap(b[0], b[3]), std::swap(b[1], b[2]);
    position_ += 4;
    return static_cast<uint32_t>(b[0]) | (static_cast<uint32_t>(b[1]) << 8) |
           (static_cast<uint32_t>(b[2]) << 16) | (static_cast<uint32_t>(b[3]) << 24);
  }
  const uint8_t* bytes(size_t n, const char* field) {
    need(n, field);
    const uint8_t* start = data_ + position_;
    position_ += n;
    return start;
  }
  void skip(size_t n, const char* field) { bytes(n, field); }
  size_t left() const { return size_ - position_; }
  // A header stamp or packet stamp: int32/uint32 sec, uint32 nsec (< 1e9).
  TimeNs stamp(const char* field) {
    const uint32_t sec = u32(field);
    const uint32_t nsec = u32(field);
    if (nsec >= 1000000000u)
      throw IoError(std::string("VelodyneScan: field '") + field + "' has " + std::to_string(nsec) +
                    " nanoseconds");
    return static_cast<TimeNs>(sec) * 1000000000 + nsec;
  }

 private:
  void need(size_t n, const char* field) const {
    if (n > size_ - position_)
      throw IoError(std::string("VelodyneScan: field '") + field + "' (" + std::to_string(n) +
                    " bytes at offset " + std::to_string(position_) +
                    ") runs past the end of the " + std::to_string(size_) + "-byte message");
  }
  const uint8_t* data_;
  size_t size_;
  size_t position_;
  size_t origin_;
  bool swap_;
};

// Packet count against the bytes left, so a corrupt count fails before any allocation.
void check_count(uint32_t count, size_t bytes_each, size_t left) {
  if (count > left / bytes_each + 1)
    throw IoError("VelodyneScan: field 'packets' claims " + std::to_string(count) +
                  " packets; the message holds at most " + std::to_string(left / bytes_each + 1));
}

}  // namespace

VelodyneScanView parse_velodyne_scan_ros1(const uint8_t* data, size_t size) {
  Cursor in(data, size, 0, 0, false);
  VelodyneScanView scan;
  in.u32("header.seq");
  scan.stamp_ns = in.stamp("header.stamp");
  in.skip(in.u32("header.frame_id"), "header.frame_id");
  const uint32_t count = in.u32("packets");
  check_count(count, 8 + kVelodynePacketBytes, in.left());
  scan.packets.reserve(count);
  for (uint32_t i = 0; i < count; ++i) {
    VelodynePacketView& packet = scan.packets.emplace_back();
    packet.stamp_ns = in.stamp("packets[].stamp");
    packet.data = in.bytes(kVelodynePacketBytes, "packets[].data");
  }
  return scan;
}

VelodyneScanView parse_velodyne_scan_cdr(const uint8_t* data, size_t size) {
  if (size < 4) throw IoError("VelodyneScan: CDR message shorter than its 4-byte header");
  // Encapsulation id (RTPS 2.5 §10.2): odd = little endian; plain CDR and XCDR2 align 4-byte
  // fields alike, and this message has no wider ones.
  const uint16_t kind = static_cast<uint16_t>(data[0] << 8 | data[1]);
  if (kind != 0x0000 && kind != 0x0001 && kind != 0x0006 && kind != 0x0007)
    throw IoError("VelodyneScan: CDR encapsulation " + std::to_string(kind) +
                  " is not plain CDR or plain XCDR2");
  Cursor in(data, size, 4, 4, (kind & 1) == 0);
  VelodyneScanView scan;
  scan.stamp_ns = in.stamp("header.stamp");
  in.skip(in.u32("header.frame_id"), "header.frame_id");
  in.align(4);
  const uint32_t count = in.u32("packets");
  check_count(count, 8 + kVelodynePacketBytes + 2, in.left());
  scan.packets.reserve(count);
  for (uint32_t i = 0; i < count; ++i) {
    in.align(4);
    VelodynePacketView& packet = scan.packets.emplace_back();
    packet.stamp_ns = in.stamp("packets[].stamp");
    packet.data = in.bytes(kVelodynePacketBytes, "packets[].data");
  }
  return scan;
}

PointCloud decode_velodyne_scan(const VelodyneScanView& scan, TimeNs fallback_stamp_ns,
                                const VelodyneCalibration& calibration,
                                const VelodyneDecodeOptions& options, const std::string& what,
                                std::vector<VelodynePoint>& scratch) {
  PointCloud cloud;
  const size_t n = scan.packets.size();
  if (n == 0) {
    cloud.t_ns = scan.stamp_ns ? scan.stamp_ns : fallback_stamp_ns;
    return cloud;
  }
  auto stamp_of = [&](size_t k) {
    const TimeNs t = scan.packets[k].stamp_ns;
    return t ? t : (scan.stamp_ns ? scan.stamp_ns : fallback_stamp_ns);
  };
  cloud.t_ns = stamp_of(0);

  // Packet offsets from the sensor's microsecond clock (rolls over every hour).
  constexpr int64_t kHourUs = 3600LL * 1000000;
  std::vector<double> offset_s(n, 0.0);
  bool clock_agrees = true;
  uint32_t first_us = 0;
  for (size_t k = 0; k < n; ++k) {
    uint32_t us = 0;
    try {
      us = velodyne_packet_info(scan.packets[k].data, kVelodynePacketBytes).timestamp_us;
    } catch (const IoError& e) {
      throw IoError(what + " packet " + std::to_string(k) + ": " + e.what());
    }
    if (k == 0) first_us = us;
    const int64_t delta_us = ((static_cast<int64_t>(us) - first_us) % kHourUs + kHourUs) % kHourUs;
    offset_s[k] = delta_us * 1e-6;
    const double by_stamp = (stamp_of(k) - cloud.t_ns) * 1e-9;
    if (std::abs(offset_s[k] - by_stamp) > 0.05) clock_agrees = false;
  }
  if (!clock_agrees)
    for (size_t k = 0; k < n; ++k) offset_s[k] = (stamp_of(k) - cloud.t_ns) * 1e-9;

  const size_t per_packet = kVelodyneBlocks * 32;
  cloud.xyz.reserve(n * per_packet);
  cloud.intensity.reserve(n * per_packet);
  cloud.ring.reserve(n * per_packet);
  cloud.time_s.reserve(n * per_packet);
  for (size_t k = 0; k < n; ++k) {
    scratch.clear();
    try {
      decode_velodyne_packet(scan.packets[k].data, kVelodynePacketBytes, calibration, options,
                             scratch);
    } catch (const IoError& e) {
      throw IoError(what + " packet " + std::to_string(k) + ": " + e.what());
    }
    for (const VelodynePoint& p : scratch) {
      cloud.xyz.emplace_back(p.x, p.y, p.z);
      cloud.intensity.push_back(p.intensity);
      cloud.ring.push_back(p.ring);
      cloud.time_s.push_back(static_cast<float>(offset_s[k] + p.time_s));
    }
  }
  return cloud;
}

}  // namespace keel::io::lidar
