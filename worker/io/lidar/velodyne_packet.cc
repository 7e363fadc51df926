#include "worker/io/lidar/velodyne_packet.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "worker/io/io_error.h"

namespace keel::io::lidar {

namespace {

constexpr double kCentidegToRad = M_PI / 18000.0;
// A step between successive firing groups larger than this is a gap (field-of-view-limited
// stream, dropped blocks), not rotation: even at 1200 rpm a VLP-16 group turns 0.8 deg.
constexpr double kMaxGroupStepCdeg = 200.0;

uint16_t u16_at(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t u32_at(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}

std::string hex(unsigned value, int digits = 2) {
  char text[12];
  std::snprintf(text, sizeof(text), "0x%0*X", digits, value);
  return text;
}

// sin/cos of every 0.01 deg, for round_azimuth_to_centidegree.
struct CentidegreeTable {
  std::array<float, 36000> sin_, cos_;
  CentidegreeTable() {
    for (int i = 0; i < 36000; ++i) {
      sin_[i] = static_cast<float>(std::sin(i * kCentidegToRad));
      cos_[i] = static_cast<float>(std::cos(i * kCentidegToRad));
    }
  }
};
const CentidegreeTable& centidegree_table() {
  static const CentidegreeTable table;
  return table;
}

}  // namespace

double velodyne_group_duration_s(VelodyneModel model) {
  switch (model) {
    case VelodyneModel::kVlp16:
      return 2 * 55.296e-6;
    case VelodyneModel::kVlp32c:
      return 55.296e-6;
    case VelodyneModel::kHdl32e:
      return 46.080e-6;
  }
  return 0;
}

double velodyne_slot_offset_s(VelodyneModel model, size_t slot) {
  switch (model) {
    case VelodyneModel::kVlp16:
      return (slot / 16) * 55.296e-6 + (slot % 16) * 2.304e-6;
    case VelodyneModel::kVlp32c:
      return (slot / 2) * 2.304e-6;
    case VelodyneModel::kHdl32e:
      return slot * 1.152e-6;
  }
  return 0;
}

size_t velodyne_slot_laser(VelodyneModel model, size_t slot) {
  return model == VelodyneModel::kVlp16 ? slot % 16 : slot;
}

VelodynePacketInfo velodyne_packet_info(const uint8_t* data, size_t size) {
  if (size != kVelodynePacketBytes)
    throw IoError("a Velodyne data packet has " + std::to_string(kVelodynePacketBytes) +
                  " bytes, this one " + std::to_string(size));
  VelodynePacketInfo info;
  info.timestamp_us = u32_at(data + 1200);
  info.return_mode = data[1204];
  info.product_id = data[1205];
  return info;
}

VelodynePacketInfo decode_velodyne_packet(const uint8_t* data, size_t size,
                                          const VelodyneCalibration& calibration,
                                          const VelodyneDecodeOptions& options,
                                          std::vector<VelodynePoint>& out) {
  const VelodynePacketInfo info = velodyne_packet_info(data, size);
  const VelodyneModel model = calibration.model;
  const bool unspecified = info.return_mode == 0 && info.product_id == 0;
  if (!unspecified) {
    if (info.return_mode < 0x37 || info.return_mode > 0x39)
      throw IoError("unknown return mode byte " + hex(info.return_mode) +
                    " (0x37 strongest, 0x38 last, 0x39 dual)");
    if (info.product_id != product_id(model))
      throw IoError("product id byte " + hex(info.product_id) + " is not a " + to_string(model) +
                    " (" + hex(product_id(model)) + ")");
  }
  if (calibration.lasers.size() != laser_count(model))
    throw IoError("calibration has " + std::to_string(calibration.lasers.size()) + " lasers; a " +
                  to_string(model) + " has " + std::to_string(laser_count(model)));
  const bool dual = info.return_mode == static_cast<uint8_t>(VelodyneReturnMode::kDual);
  const size_t blocks_per_group = dual ? 2 : 1;
  const size_t groups = kVelodyneBlocks / blocks_per_group;

  // Group azimuths (cdeg) and the rotation rate each group sweeps at (cdeg per s).
  std::array<double, kVelodyneBlocks> group_azimuth{}, group_rate{};
  for (size_t b = 0; b < kVelodyneBlocks; ++b) {
    const uint8_t* block = data + b * kVelodyneBlockBytes;
    const uint16_t flag = u16_at(block);
    if (flag != kVelodyneBlockFlag)
      throw IoError("block " + std::to_string(b) + " starts with " + hex(flag, 4) +
                    ", not the block flag 0xEEFF");
    const uint16_t azimuth = u16_at(block + 2);
    if (azimuth >= 36000)
      throw IoError("block " + std::to_string(b) + " azimuth " + std::to_string(azimuth) +
                    " is not below 36000 (0.01 deg)");
    if (b % blocks_per_group == 0) group_azimuth[b / blocks_per_group] = azimuth;
  }
  const double duration_s = velodyne_group_duration_s(model);
  std::array<bool, kVelodyneBlocks> rate_known{};
  for (size_t g = 0; g + 1 < groups; ++g) {
    const double step = std::fmod(group_azimuth[g + 1] - group_azimuth[g] + 36000.0, 36000.0);
    rate_known[g] = step <= kMaxGroupStepCdeg;
    group_rate[g] = rate_known[g] ? step / duration_s : 0.0;
  }
  // Groups without a measured rate (the last one, gaps) take the nearest earlier one, else
  // the nearest later one.
  for (size_t g = 0; g < groups; ++g) {
    if (rate_known[g]) continue;
    bool found = false;
    for (size_t k = g; k-- > 0 && !found;)
      if (rate_known[k]) group_rate[g] = group_rate[k], found = true;
    for (size_t k = g + 1; k < groups && !found; ++k)
      if (rate_known[k]) group_rate[g] = group_rate[k], found = true;
  }

  const float resolution = static_cast<float>(calibration.distance_resolution_m);
  const CentidegreeTable* table =
      options.round_azimuth_to_centidegree ? &centidegree_table() : nullptr;
  for (size_t b = 0; b < kVelodyneBlocks; ++b) {
    const uint8_t* block = data + b * kVelodyneBlockBytes;
    const uint8_t* other = dual ? data + (b ^ 1) * kVelodyneBlockBytes : nullptr;
    const size_t g = b / blocks_per_group;
    const double group_start_s = g * duration_s;
    const uint16_t block_azimuth = u16_at(block + 2);
    for (size_t slot = 0; slot < 32; ++slot) {
      const uint8_t* point = block + 4 + slot * 3;
      const uint16_t raw = u16_at(point);
      if (raw == 0) continue;
      if (dual && (b & 1) && !options.keep_duplicate_returns && u16_at(other + 4 + slot * 3) == raw)
        continue;
      const size_t laser_id = velodyne_slot_laser(model, slot);
      const VelodyneLaser& laser = calibration.lasers[laser_id];
      const float distance = raw * resolution + static_cast<float>(laser.dist_correction_m);
      if (!(distance > options.min_range_m && distance < options.max_range_m)) continue;
      const double offset_s = velodyne_slot_offset_s(model, slot);
      double azimuth_cdeg = group_azimuth[g];
      if (options.interpolate_azimuth) azimuth_cdeg += group_rate[g] * offset_s;
      float sin_a, cos_a;
      if (table) {
        const int index = static_cast<int>(std::lround(azimuth_cdeg)) % 36000;
        azimuth_cdeg = index;
        sin_a = table->sin_[index];
        cos_a = table->cos_[index];
      } else {
        if (azimuth_cdeg >= 36000.0) azimuth_cdeg -= 36000.0;
        const double a = azimuth_cdeg * kCentidegToRad;
        sin_a = static_cast<float>(std::sin(a));
        cos_a = static_cast<float>(std::cos(a));
      }
      // alpha = azimuth - rot_correction (velodyne_calibration.h)
      const float cos_alpha = cos_a * laser.cos_rot + sin_a * laser.sin_rot;
      const float sin_alpha = sin_a * laser.cos_rot - cos_a * laser.sin_rot;
      const float vert_offset = static_cast<float>(laser.vert_offset_m);
      const float horiz_offset = static_cast<float>(laser.horiz_offset_m);
      const float xy = distance * laser.cos_vert - vert_offset * laser.sin_vert;
      VelodynePoint& p = out.emplace_back();
      p.x = xy * cos_alpha + horiz_offset * sin_alpha;
      p.y = -(xy * sin_alpha - horiz_offset * cos_alpha);
      p.z = distance * laser.sin_vert + vert_offset * laser.cos_vert;
      p.distance_m = distance;
      p.azimuth_rad = static_cast<float>(azimuth_cdeg * kCentidegToRad);
      p.intensity = point[2];
      p.time_s = group_start_s + offset_s;
      p.ring = laser.ring;
      p.block_azimuth_cdeg = block_azimuth;
      p.laser = static_cast<uint8_t>(laser_id);
      p.block = static_cast<uint8_t>(b);
      p.return_index = static_cast<uint8_t>(dual ? (b & 1) : 0);
    }
  }
  return info;
}

}  // namespace keel::io::lidar
