// Decodes one Velodyne data packet (the 1206-byte UDP payload a VelodyneScan message holds per
// packet) into points with each point's firing time. No I/O. Layout (VLP-16, VLP-32C and
// HDL-32E user manuals, "Data Packet Format"): 12 blocks of 100 bytes, each a uint16 flag
// 0xEEFF, a uint16 azimuth (0.01 deg, 0..35999) and 32 data points of uint16 distance
// (distance_resolution_m units, 0 = no return) + uint8 reflectivity; a uint32 timestamp
// (us past the top of the hour, of the packet's first firing); 2 factory bytes: return mode
// (0x37 strongest, 0x38 last, 0x39 dual) and product id (0x22 VLP-16, 0x28 VLP-32C, 0x21
// HDL-32E). All little-endian.
//
// Firing times (manuals, "Precision Azimuth Calculation" / "Laser Firing Sequence"):
//   VLP-16:  a block holds 2 firing sequences of 16 lasers; 55.296 us per sequence, 2.304 us
//            per laser: t = (2 g + seq) 55.296 + laser 2.304 us
//   VLP-32C: a block is one sequence, lasers fire in pairs every 2.304 us:
//            t = g 55.296 + (laser / 2) 2.304 us
//   HDL-32E: a block is one sequence, 1.152 us per laser: t = g 46.080 + laser 1.152 us
// where g counts firing groups: a block in single-return modes, a pair of blocks (same firing,
// last return in the even block, strongest or second-strongest in the odd one) in dual mode.
// Each firing's azimuth is interpolated between its group's azimuth and the next group's, at
// the rate measured between them (the last group takes the previous group's rate; a step of
// more than 2 degrees, a gap in a field-of-view-limited stream, is not a rate either).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "worker/io/lidar/velodyne_calibration.h"

namespace keel::io::lidar {

constexpr size_t kVelodynePacketBytes = 1206;
constexpr size_t kVelodyneBlocks = 12;
constexpr size_t kVelodyneBlockBytes = 100;
constexpr uint16_t kVelodyneBlockFlag = 0xEEFF;

enum class VelodyneReturnMode : uint8_t { kStrongest = 0x37, kLast = 0x38, kDual = 0x39 };

struct VelodynePoint {
  float x = 0, y = 0, z = 0;        // m, sensor frame (x forward, y left, z up)
  float distance_m = 0;             // after the laser's distance correction
  float azimuth_rad = 0;            // encoder azimuth of the firing (before the laser's rot offset)
  float intensity = 0;              // reflectivity byte
  double time_s = 0;                // firing time after the packet's first firing
  uint16_t ring = 0;                // calibration ring (0 = lowest elevation)
  uint16_t block_azimuth_cdeg = 0;  // the block's raw azimuth (0.01 deg)
  uint8_t laser = 0;                // laser_id: position in the block
  uint8_t block = 0;                // 0..11
  uint8_t return_index = 0;         // 0: single return, or dual's even block; 1: dual's odd block
};

struct VelodyneDecodeOptions {
  // Returns kept when min_range_m < distance < max_range_m (the drivers' exclusive bounds).
  double min_range_m = 0.0;
  double max_range_m = 1e9;
  // Per-firing azimuth as the manuals say; false: every laser of a block at the block's
  // azimuth (what nebula's VLP-32 and HDL decoders do).
  bool interpolate_azimuth = true;
  // Round each firing's azimuth to the encoder's 0.01 deg before the trigonometry (what
  // velodyne_pointcloud and nebula's VLP-16 decoder do, with 36000-entry tables).
  bool round_azimuth_to_centidegree = false;
  // Dual mode: keep an odd block's return whose distance equals the even block's.
  bool keep_duplicate_returns = false;
};

struct VelodynePacketInfo {
  uint32_t timestamp_us = 0;  // past the top of the hour
  uint8_t return_mode = 0;    // raw byte 1204
  uint8_t product_id = 0;     // raw byte 1205
};

// Reads the packet's timestamp and factory bytes, checking the size only.
VelodynePacketInfo velodyne_packet_info(const uint8_t* data, size_t size);

// Appends the packet's returns to `out` in data order (block, firing, laser). Throws IoError
// saying what is wrong (size, a block flag, an azimuth >= 36000, an unknown return mode, a
// product id other than the calibration's model; 0 factory bytes are accepted as older
// firmware's "strongest, unspecified model"); the caller names the topic, message and packet.
VelodynePacketInfo decode_velodyne_packet(const uint8_t* data, size_t size,
                                          const VelodyneCalibration& calibration,
                                          const VelodyneDecodeOptions& options,
                                          std::vector<VelodynePoint>& out);

// Seconds of one firing group (the span a block, or a dual pair, covers): 110.592 us VLP-16,
// 55.296 us VLP-32C, 46.080 us HDL-32E.
double velodyne_group_duration_s(VelodyneModel model);
// Firing time of data point `slot` (0..31) of a block after its group's start.
double velodyne_slot_offset_s(VelodyneModel model, size_t slot);
// Laser id of data point `slot` of a block (VLP-16: slot % 16).
size_t velodyne_slot_laser(VelodyneModel model, size_t slot);

}  // namespace keel::io::lidar
