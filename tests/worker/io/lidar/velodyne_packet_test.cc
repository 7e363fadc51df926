// Packets encoded from known returns (closed form: rotation at a constant rate, the manuals'
// firing tables, the calibration's geometry) decode back to the same points and times.
#include "worker/io/lidar/velodyne_packet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "worker/io/io_error.h"

namespace keel::io::lidar {
namespace {

struct Packet {
  std::vector<uint8_t> bytes = std::vector<uint8_t>(kVelodynePacketBytes, 0);
  void u16(size_t at, uint16_t v) { bytes[at] = v & 0xFF, bytes[at + 1] = v >> 8; }
};

// Firing time of a slot from the manuals' tables, written out per model (not via the
// decoder's helpers).
double firing_time_us(VelodyneModel model, size_t group, size_t slot) {
  switch (model) {
    case VelodyneModel::kVlp16:
      return (2 * group + slot / 16) * 55.296 + (slot % 16) * 2.304;
    case VelodyneModel::kVlp32c:
      return group * 55.296 + (slot / 2) * 2.304;
    case VelodyneModel::kHdl32e:
      return group * 46.080 + slot * 1.152;
  }
  return 0;
}
double group_us(VelodyneModel model) {
  return model == VelodyneModel::kVlp16    ? 110.592
         : model == VelodyneModel::kVlp32c ? 55.296
                                           : 46.080;
}

struct Expected {
  double x, y, z, t_s, distance;
  int laser, return_index;
  uint8_t intensity;
};

// A calibration with every correction non-zero, so each term of the geometry is checked.
VelodyneCalibration test_calibration(VelodyneModel model) {
  VelodyneCalibration c = factory_calibration(model);
  for (size_t i = 0; i < c.lasers.size(); ++i) {
    c.lasers[i].rot_rad += 0.001 * static_cast<double>(i % 5);
    c.lasers[i].dist_correction_m = 0.01 * static_cast<double>(i % 3);
    c.lasers[i].vert_offset_m = 0.002 * static_cast<double>(i % 4);
    c.lasers[i].horiz_offset_m = -0.003 * static_cast<double>(i % 2);
  }
  c.finalise();
  return c;
}

// Encodes a packet turning at `deg_per_s` from `azimuth0_cdeg`; returns the points it holds.
std::vector<Expected> encode(VelodyneModel model, bool dual, double azimuth0_cdeg,
                             double cdeg_per_us, const VelodyneCalibration& cal, Packet& packet,
                             std::mt19937& rng) {
  std::vector<Expected> expected;
  std::uniform_int_distribution<int> raw_distance(100, 30000), intensity(0, 255), coin(0, 3);
  const size_t per_group = dual ? 2 : 1;
  for (size_t b = 0; b < 12; ++b) {
    const size_t g = b / per_group;
    const double group_azimuth = std::round(azimuth0_cdeg + cdeg_per_us * g * group_us(model));
    const size_t at = b * 100;
    packet.u16(at, 0xEEFF);
    packet.u16(at + 2, static_cast<uint16_t>(std::fmod(group_azimuth, 36000.0)));
    for (size_t slot = 0; slot < 32; ++slot) {
      int raw = coin(rng) == 0 ? 0 : raw_distance(rng);  // some slots without a return
      if (dual && (b & 1) && coin(rng) == 0) {           // some second returns equal the first
        raw = packet.bytes[at - 100 + 4 + slot * 3] | (packet.bytes[at - 100 + 5 + slot * 3] << 8);
      }
      const uint8_t refl = static_cast<uint8_t>(intensity(rng));
      packet.u16(at + 4 + slot * 3, static_cast<uint16_t>(raw));
      packet.bytes[at + 6 + slot * 3] = refl;
      const bool duplicate = dual && (b & 1) &&
                             raw == (packet.bytes[at - 100 + 4 + slot * 3] |
                                     (packet.bytes[at - 100 + 5 + slot * 3] << 8));
      if (raw == 0 || duplicate) continue;
      const int laser_id = static_cast<int>(model == VelodyneModel::kVlp16 ? slot % 16 : slot);
      const VelodyneLaser& laser = cal.lasers[laser_id];
      const double t_us = firing_time_us(model, g, slot);
      // The group's azimuth plus the constant rate over the firing's delay in the group
      // (the rate the decoder measures between rounded group azimuths).
      // The last group has no next one: the rate before it (the manuals' extrapolation).
      auto group_at = [&](size_t k) {
        return std::round(azimuth0_cdeg + cdeg_per_us * k * group_us(model));
      };
      const size_t last = 12 / per_group - 1;
      const double rate = g < last ? (group_at(g + 1) - group_at(g)) / group_us(model)
                                   : (group_at(g) - group_at(g - 1)) / group_us(model);
      const double azimuth = (group_azimuth + rate * (t_us - g * group_us(model))) * M_PI / 18000.0;
      const double d = raw * cal.distance_resolution_m + laser.dist_correction_m;
      const double alpha = azimuth - laser.rot_rad;
      const double xy =
          d * std::cos(laser.vert_rad) - laser.vert_offset_m * std::sin(laser.vert_rad);
      expected.push_back(
          {xy * std::cos(alpha) + laser.horiz_offset_m * std::sin(alpha),
           -(xy * std::sin(alpha) - laser.horiz_offset_m * std::cos(alpha)),
           d * std::sin(laser.vert_rad) + laser.vert_offset_m * std::cos(laser.vert_rad),
           t_us * 1e-6, d, laser_id, dual ? static_cast<int>(b & 1) : 0, refl});
    }
  }
  packet.bytes[1200] = 0x78, packet.bytes[1201] = 0x56, packet.bytes[1202] = 0x34,
  packet.bytes[1203] = 0x12;
  packet.bytes[1204] = dual ? 0x39 : 0x37;
  packet.bytes[1205] = product_id(model);
  return expected;
}

void check_round_trip(VelodyneModel model, bool dual) {
  SCOPED_TRACE(to_string(model) + (dual ? " dual" : " strongest"));
  const VelodyneCalibration cal = test_calibration(model);
  std::mt19937 rng(7);
  // 600 rpm = 3600 deg/s = 0.36 cdeg/us, starting near the wrap so it is crossed.
  Packet packet;
  const auto expected = encode(model, dual, 35950.0, 0.36, cal, packet, rng);
  std::vector<VelodynePoint> points;
  const VelodynePacketInfo info =
      decode_velodyne_packet(packet.bytes.data(), packet.bytes.size(), cal, {}, points);
  EXPECT_EQ(info.timestamp_us, 0x12345678u);
  ASSERT_EQ(points.size(), expected.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const VelodynePoint& p = points[i];
    const Expected& e = expected[i];
    EXPECT_NEAR(p.x, e.x, 2e-5 * (1 + e.distance)) << i;
    EXPECT_NEAR(p.y, e.y, 2e-5 * (1 + e.distance)) << i;
    EXPECT_NEAR(p.z, e.z, 2e-5 * (1 + e.distance)) << i;
    EXPECT_NEAR(p.time_s, e.t_s, 1e-12) << i;
    EXPECT_NEAR(p.distance_m, e.distance, 1e-6 * (1 + e.distance)) << i;
    EXPECT_EQ(p.laser, e.laser) << i;
    EXPECT_EQ(p.ring, cal.lasers[e.laser].ring) << i;
    EXPECT_EQ(p.return_index, e.return_index) << i;
    EXPECT_EQ(p.intensity, e.intensity) << i;
  }
}

TEST(VelodynePacket, Vlp16StrongestRoundTrip) { check_round_trip(VelodyneModel::kVlp16, false); }
TEST(VelodynePacket, Vlp16DualRoundTrip) { check_round_trip(VelodyneModel::kVlp16, true); }
TEST(VelodynePacket, Vlp32cStrongestRoundTrip) { check_round_trip(VelodyneModel::kVlp32c, false); }
TEST(VelodynePacket, Vlp32cDualRoundTrip) { check_round_trip(VelodyneModel::kVlp32c, true); }
TEST(VelodynePacket, Hdl32eStrongestRoundTrip) { check_round_trip(VelodyneModel::kHdl32e, false); }
TEST(VelodynePacket, Hdl32eDualRoundTrip) { check_round_trip(VelodyneModel::kHdl32e, true); }

TEST(VelodynePacket, FiringTablesOfTheManuals) {
  // Last firing of a packet: VLP-16 24 sequences of 55.296 us; VLP-32C 12 blocks of 55.296
  // us, 16 pairs; HDL-32E 12 blocks of 46.08 us, 32 lasers.
  EXPECT_NEAR(5 * velodyne_group_duration_s(VelodyneModel::kVlp16) +
                  velodyne_slot_offset_s(VelodyneModel::kVlp16, 31),
              (11 * 55.296 + 15 * 2.304) * 1e-6, 1e-12);
  EXPECT_NEAR(velodyne_slot_offset_s(VelodyneModel::kVlp32c, 31), 15 * 2.304e-6, 1e-12);
  EXPECT_NEAR(velodyne_slot_offset_s(VelodyneModel::kHdl32e, 31), 31 * 1.152e-6, 1e-12);
}

TEST(VelodynePacket, RangeLimitsAreExclusive) {
  const VelodyneCalibration cal = factory_calibration(VelodyneModel::kVlp16);
  Packet packet;
  for (size_t b = 0; b < 12; ++b) {
    packet.u16(b * 100, 0xEEFF);
    packet.u16(b * 100 + 2, static_cast<uint16_t>(b * 20));
    packet.u16(b * 100 + 4, 500);   // 1.0 m
    packet.u16(b * 100 + 7, 1000);  // 2.0 m
  }
  packet.bytes[1204] = 0x37, packet.bytes[1205] = 0x22;
  VelodyneDecodeOptions options;
  options.min_range_m = 1.0;
  options.max_range_m = 2.5;
  std::vector<VelodynePoint> points;
  decode_velodyne_packet(packet.bytes.data(), packet.bytes.size(), cal, options, points);
  ASSERT_EQ(points.size(), 12u);
  for (const auto& p : points) EXPECT_FLOAT_EQ(p.distance_m, 2.0f);
}

TEST(VelodynePacket, BadPacketsAreErrorsSayingWhat) {
  const VelodyneCalibration cal = factory_calibration(VelodyneModel::kVlp16);
  std::vector<VelodynePoint> points;
  Packet packet;
  for (size_t b = 0; b < 12; ++b) packet.u16(b * 100, 0xEEFF);
  packet.bytes[1204] = 0x37, packet.bytes[1205] = 0x22;
  auto message = [&](const std::vector<uint8_t>& bytes, const VelodyneCalibration& c) {
    try {
      decode_velodyne_packet(bytes.data(), bytes.size(), c, {}, points);
    } catch (const IoError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(packet.bytes, cal), "no error");
  EXPECT_NE(message(std::vector<uint8_t>(packet.bytes.begin(), packet.bytes.end() - 1), cal)
                .find("1206 bytes, this one 1205"),
            std::string::npos);
  Packet flag = packet;
  flag.u16(300, 0xDDFF);
  EXPECT_NE(message(flag.bytes, cal).find("block 3 starts with 0xDDFF"), std::string::npos);
  Packet azimuth = packet;
  azimuth.u16(502, 36000);
  EXPECT_NE(message(azimuth.bytes, cal).find("block 5 azimuth 36000"), std::string::npos);
  Packet mode = packet;
  mode.bytes[1204] = 0x40;
  EXPECT_NE(message(mode.bytes, cal).find("return mode byte 0x40"), std::string::npos);
  EXPECT_NE(message(packet.bytes, factory_calibration(VelodyneModel::kVlp32c))
                .find("product id byte 0x22 is not a VLP32C (0x28)"),
            std::string::npos);
}

}  // namespace
}  // namespace keel::io::lidar
