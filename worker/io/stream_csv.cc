#include "worker/io/stream_csv.h"

#include "worker/io/csv_reader.h"
#include "worker/io/text_writer.h"

namespace keel::io {

ImuSeries read_imu_csv(const std::filesystem::path& path) {
  CsvReader csv(path, {"t", "wx", "wy", "wz", "ax", "ay", "az"});
  ImuSeries out;
  while (csv.next()) {
    ImuSample s;
    s.t_ns = csv.time(0);
    csv.check_increasing(s.t_ns);
    s.gyro_rad_s = {csv.number(1), csv.number(2), csv.number(3)};
    s.accel_m_s2 = {csv.number(4), csv.number(5), csv.number(6)};
    out.push_back(s);
  }
  return out;
}

DvlSeries read_dvl_csv(const std::filesystem::path& path) {
  CsvReader csv(path, {"t", "vx", "vy", "vz"}, {"valid"});
  DvlSeries out;
  while (csv.next()) {
    DvlSample s;
    s.t_ns = csv.time(0);
    csv.check_increasing(s.t_ns);
    if (csv.has_column(4)) {
      const double valid = csv.number(4);
      if (valid != 0.0 && valid != 1.0) csv.fail("column 'valid': expected 0 or 1");
      s.valid = valid == 1.0;
    }
    // A dropout row may carry nan velocities; a valid row may not.
    s.velocity_m_s = {csv.number(1, !s.valid), csv.number(2, !s.valid), csv.number(3, !s.valid)};
    out.push_back(s);
  }
  return out;
}

DvlRangesSeries read_dvl_ranges_csv(const std::filesystem::path& path) {
  CsvReader csv(path, {"t", "r0", "r1", "r2", "r3"});
  DvlRangesSeries out;
  while (csv.next()) {
    DvlRangesSample s;
    s.t_ns = csv.time(0);
    csv.check_increasing(s.t_ns);
    for (size_t beam = 0; beam < 4; ++beam)
      s.range_m[beam] = csv.number(1 + beam, /*allow_nan=*/true);
    out.push_back(s);
  }
  return out;
}

namespace {

// A `t,<column>` file into samples whose one value is `field`.
template <typename Sample>
std::vector<Sample> read_scalar_csv(const std::filesystem::path& path, const char* column,
                                    double Sample::*field) {
  CsvReader csv(path, {"t", column});
  std::vector<Sample> out;
  while (csv.next()) {
    Sample s;
    s.t_ns = csv.time(0);
    csv.check_increasing(s.t_ns);
    s.*field = csv.number(1);
    out.push_back(s);
  }
  return out;
}

}  // namespace

DepthSeries read_depth_csv(const std::filesystem::path& path) {
  return read_scalar_csv(path, "depth", &DepthSample::depth_m);
}

ServoSeries read_servo_csv(const std::filesystem::path& path) {
  return read_scalar_csv(path, "angle", &ServoSample::angle_rad);
}

void write_imu_csv(const std::filesystem::path& path, const ImuSeries& samples) {
  TextWriter w(path);
  w.text("t,wx,wy,wz,ax,ay,az\n");
  for (const auto& s : samples) {
    w.seconds(s.t_ns);
    for (int i = 0; i < 3; ++i) w.text(",").number(s.gyro_rad_s[i]);
    for (int i = 0; i < 3; ++i) w.text(",").number(s.accel_m_s2[i]);
    w.text("\n");
  }
  w.close();
}

void write_dvl_csv(const std::filesystem::path& path, const DvlSeries& samples, bool with_valid) {
  for (const auto& s : samples) with_valid = with_valid || !s.valid;
  TextWriter w(path);
  w.text(with_valid ? "t,vx,vy,vz,valid\n" : "t,vx,vy,vz\n");
  for (const auto& s : samples) {
    w.seconds(s.t_ns);
    for (int i = 0; i < 3; ++i) w.text(",").number(s.velocity_m_s[i]);
    if (with_valid) w.text(s.valid ? ",1" : ",0");
    w.text("\n");
  }
  w.close();
}

void write_dvl_ranges_csv(const std::filesystem::path& path, const DvlRangesSeries& samples) {
  TextWriter w(path);
  w.text("t,r0,r1,r2,r3\n");
  for (const auto& s : samples) {
    w.seconds(s.t_ns);
    for (double r : s.range_m) w.text(",").number(r);
    w.text("\n");
  }
  w.close();
}

void write_depth_csv(const std::filesystem::path& path, const DepthSeries& samples) {
  TextWriter w(path);
  w.text("t,depth\n");
  for (const auto& s : samples) w.seconds(s.t_ns).text(",").number(s.depth_m).text("\n");
  w.close();
}

void write_servo_csv(const std::filesystem::path& path, const ServoSeries& samples) {
  TextWriter w(path);
  w.text("t,angle\n");
  for (const auto& s : samples) w.seconds(s.t_ns).text(",").number(s.angle_rad).text("\n");
  w.close();
}

}  // namespace keel::io
