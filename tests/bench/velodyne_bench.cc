// Velodyne packet decoding throughput on one core (target >= 5 M points/s): Keel's decoder
// (worker/io/lidar/velodyne_packet.h) with per-firing azimuths, the same rounded to 0.01 deg
// (table lookups), and a peer in this process: a naive decoder doing every point's
// trigonometry in double from the angles (azimuth, laser elevation and offset) with no cached
// values, what a first implementation of the manual's formulas looks like. Packets are
// synthetic (600 rpm, every slot a return). Prints points/s of each (column points/s).
// Run: build/tests/bench/bench_velodyne
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "worker/io/lidar/velodyne_packet.h"

namespace {

using namespace keel::io::lidar;

constexpr size_t kPackets = 754;  // one second of a single-return VLP-16

std::vector<std::vector<uint8_t>> make_packets(VelodyneModel model) {
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> distance(500, 40000);
  std::vector<std::vector<uint8_t>> packets(kPackets, std::vector<uint8_t>(kVelodynePacketBytes));
  const double block_us = model == VelodyneModel::kVlp16    ? 110.592
                          : model == VelodyneModel::kVlp32c ? 55.296
                                                            : 46.080;
  double azimuth = 0;
  for (auto& p : packets) {
    for (size_t b = 0; b < 12; ++b) {
      uint8_t* block = p.data() + b * 100;
      block[0] = 0xFF, block[1] = 0xEE;
      const auto a = static_cast<uint16_t>(std::fmod(std::round(azimuth), 36000.0));
      block[2] = a & 0xFF, block[3] = a >> 8;
      for (size_t s = 0; s < 32; ++s) {
        const int d = distance(rng);
        block[4 + 3 * s] = d & 0xFF, block[5 + 3 * s] = static_cast<uint8_t>(d >> 8);
        block[6 + 3 * s] = static_cast<uint8_t>(s * 7);
      }
      azimuth += 0.36 * block_us;  // 600 rpm = 0.36 cdeg per us
    }
    p[1204] = 0x37;
    p[1205] = product_id(model);
  }
  return packets;
}

// The peer: reads the same bytes, computes each point from angles in double.
size_t naive_decode(const uint8_t* data, const VelodyneCalibration& cal, std::vector<float>& xyz) {
  size_t n = 0;
  for (size_t b = 0; b < 12; ++b) {
    const uint8_t* block = data + b * 100;
    const double azimuth = (block[2] | (block[3] << 8)) * M_PI / 18000.0;
    const uint8_t* next = data + (b < 11 ? b + 1 : b) * 100;
    const double next_azimuth = (next[2] | (next[3] << 8)) * M_PI / 18000.0;
    const double rate = b < 11 ? std::remainder(next_azimuth - azimuth, 2 * M_PI) /
                                     velodyne_group_duration_s(cal.model)
                               : 0.0;
    for (size_t s = 0; s < 32; ++s) {
      const int raw = block[4 + 3 * s] | (block[5 + 3 * s] << 8);
      if (raw == 0) continue;
      const VelodyneLaser& laser = cal.lasers[velodyne_slot_laser(cal.model, s)];
      const double d = raw * cal.distance_resolution_m + laser.dist_correction_m;
      const double alpha = azimuth + rate * velodyne_slot_offset_s(cal.model, s) - laser.rot_rad;
      const double xy =
          d * std::cos(laser.vert_rad) - laser.vert_offset_m * std::sin(laser.vert_rad);
      xyz.push_back(
          static_cast<float>(xy * std::cos(alpha) + laser.horiz_offset_m * std::sin(alpha)));
      xyz.push_back(
          static_cast<float>(-(xy * std::sin(alpha) - laser.horiz_offset_m * std::cos(alpha))));
      xyz.push_back(static_cast<float>(d * std::sin(laser.vert_rad) +
                                       laser.vert_offset_m * std::cos(laser.vert_rad)));
      ++n;
    }
  }
  return n;
}

void run(benchmark::State& state, VelodyneModel model, int mode) {
  const auto packets = make_packets(model);
  const VelodyneCalibration cal = factory_calibration(model);
  VelodyneDecodeOptions options;
  options.round_azimuth_to_centidegree = mode == 1;
  std::vector<VelodynePoint> points;
  std::vector<float> xyz;
  points.reserve(400), xyz.reserve(1200);
  size_t total = 0;
  for (auto _ : state) {
    for (const auto& p : packets) {
      if (mode == 2) {
        xyz.clear();
        total += naive_decode(p.data(), cal, xyz);
        benchmark::DoNotOptimize(xyz.data());
      } else {
        points.clear();
        decode_velodyne_packet(p.data(), p.size(), cal, options, points);
        total += points.size();
        benchmark::DoNotOptimize(points.data());
      }
    }
  }
  state.counters["points/s"] =
      benchmark::Counter(static_cast<double>(total), benchmark::Counter::kIsRate);
}

void BM_Keel(benchmark::State& s, VelodyneModel m) { run(s, m, 0); }
void BM_KeelRounded(benchmark::State& s, VelodyneModel m) { run(s, m, 1); }
void BM_Naive(benchmark::State& s, VelodyneModel m) { run(s, m, 2); }

BENCHMARK_CAPTURE(BM_Keel, VLP16, VelodyneModel::kVlp16)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_KeelRounded, VLP16, VelodyneModel::kVlp16)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Naive, VLP16, VelodyneModel::kVlp16)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Keel, VLP32C, VelodyneModel::kVlp32c)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Naive, VLP32C, VelodyneModel::kVlp32c)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Keel, HDL32E, VelodyneModel::kHdl32e)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Naive, HDL32E, VelodyneModel::kHdl32e)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
