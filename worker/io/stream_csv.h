// Stream CSV files: one header line, one row per sample, strictly increasing `t` in decimal
// seconds (docs/mission-format.md). Readers fail naming file, line and column on a wrong
// header or column count, a non-number, NaN/inf (allowed only as `nan` in dvl_ranges) and a
// duplicate or decreasing stamp. Writers produce exactly what the readers accept.
#pragma once

#include <filesystem>

#include "worker/io/stream_samples.h"

namespace keel::io {

ImuSeries read_imu_csv(const std::filesystem::path& path);               // t,wx,wy,wz,ax,ay,az
DvlSeries read_dvl_csv(const std::filesystem::path& path);               // t,vx,vy,vz[,valid]
DvlRangesSeries read_dvl_ranges_csv(const std::filesystem::path& path);  // t,r0,r1,r2,r3
DepthSeries read_depth_csv(const std::filesystem::path& path);           // t,depth
ServoSeries read_servo_csv(const std::filesystem::path& path);           // t,angle

void write_imu_csv(const std::filesystem::path& path, const ImuSeries& samples);
// Writes the `valid` column when `with_valid` (or when any sample is invalid).
void write_dvl_csv(const std::filesystem::path& path, const DvlSeries& samples,
                   bool with_valid = false);
void write_dvl_ranges_csv(const std::filesystem::path& path, const DvlRangesSeries& samples);
void write_depth_csv(const std::filesystem::path& path, const DepthSeries& samples);
void write_servo_csv(const std::filesystem::path& path, const ServoSeries& samples);

}  // namespace keel::io
