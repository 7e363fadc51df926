// The CSV readers fuzz_csv_streams drives, by selector (its input's first byte): 0 IMU, 1 DVL,
// 2 DVL ranges, 3 depth, 4 servo, 5 loop closures. fuzz_seeds reads its seeds with the same.
#pragma once

#include <filesystem>

#include "worker/io/loop_closures.h"
#include "worker/io/stream_csv.h"

namespace keel::fuzz {

inline constexpr int kCsvReaders = 6;

// Reads `file` with reader `selector % kCsvReaders`; throws what the reader throws.
inline void read_csv_stream(int selector, const std::filesystem::path& file) {
  switch (selector % kCsvReaders) {
    case 0:
      (void)io::read_imu_csv(file);
      break;
    case 1:
      (void)io::read_dvl_csv(file);
      break;
    case 2:
      (void)io::read_dvl_ranges_csv(file);
      break;
    case 3:
      (void)io::read_depth_csv(file);
      break;
    case 4:
      (void)io::read_servo_csv(file);
      break;
    default:
      (void)io::read_loop_closures(file);
      break;
  }
}

}  // namespace keel::fuzz
