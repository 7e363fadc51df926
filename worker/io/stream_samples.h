// Typed samples of the stream sensors (docs/mission-format.md "Stream CSV files"). The same
// types come out of CSV files and ROS bags.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <limits>
#include <optional>
#include <vector>

#include "core/time.h"

namespace keel::io {

struct ImuSample {
  TimeNs t_ns = 0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();  // body rate in the IMU frame
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();  // specific force (+9.81 z at rest)
};

struct DvlSample {
  TimeNs t_ns = 0;
  Eigen::Vector3d velocity_m_s = Eigen::Vector3d::Zero();  // DVL w.r.t. bottom, DVL frame
  bool valid = true;                                       // false marks a dropout
  // Beam-level input (Water Linked A50, docs/mission-format.md): the beams the velocity was
  // solved from when the driver's own velocity was invalid (3 or 4; worker/io/dvl_beams.h);
  // 0 = the velocity as published. fom_m_s: the driver's figure of merit (expected error of
  // the velocity, m/s); NaN when the message has none.
  int beams_used = 0;
  double fom_m_s = std::numeric_limits<double>::quiet_NaN();
};

struct DvlRangesSample {
  TimeNs t_ns = 0;
  std::array<double, 4> range_m = {0, 0, 0, 0};  // along the four beams; NaN = no return
};

struct DepthSample {
  TimeNs t_ns = 0;
  double depth_m = 0.0;  // positive down
};

struct ServoSample {
  TimeNs t_ns = 0;
  double angle_rad = 0.0;
};

// One fix (sensor_msgs/NavSatFix, or a gnss CSV row). Covariance in the fix's local ENU
// frame, m^2, row-major (NavSatFix's position_covariance); covariance_known false when the
// message says COVARIANCE_TYPE_UNKNOWN (the sensor's noise figures are used then).
struct GnssSample {
  TimeNs t_ns = 0;
  double latitude_deg = 0.0, longitude_deg = 0.0;
  double height_m = 0.0;  // above the WGS 84 ellipsoid
  std::array<double, 9> covariance_enu_m2 = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  bool covariance_known = false;
  int status = 0;  // NavSatStatus: -1 no fix, 0 fix, 1 SBAS, 2 GBAS (RTK)
};

using ImuSeries = std::vector<ImuSample>;
using DvlSeries = std::vector<DvlSample>;
using DvlRangesSeries = std::vector<DvlRangesSample>;
using DepthSeries = std::vector<DepthSample>;
using ServoSeries = std::vector<ServoSample>;
using GnssSeries = std::vector<GnssSample>;

// Stamps of any series (for rate and gap statistics).
template <typename Series>
std::vector<TimeNs> stamps_of(const Series& series) {
  std::vector<TimeNs> stamps;
  stamps.reserve(series.size());
  for (const auto& sample : series) stamps.push_back(sample.t_ns);
  return stamps;
}

// value(sample) linearly interpolated at t_ns (stamps strictly increasing); nullopt outside
// the series.
template <typename Series, typename Value>
std::optional<double> interpolate_series(const Series& series, TimeNs t_ns, Value value) {
  if (series.empty() || t_ns < series.front().t_ns || t_ns > series.back().t_ns)
    return std::nullopt;
  auto it = std::lower_bound(series.begin(), series.end(), t_ns,
                             [](const auto& sample, TimeNs t) { return sample.t_ns < t; });
  if (it->t_ns == t_ns || it == series.begin()) return value(*it);
  const auto& a = *(it - 1);
  const auto& b = *it;
  const double s = double(t_ns - a.t_ns) / double(b.t_ns - a.t_ns);
  return (1.0 - s) * value(a) + s * value(b);
}

}  // namespace keel::io
