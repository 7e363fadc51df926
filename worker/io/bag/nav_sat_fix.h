// sensor_msgs/NavSatFix (ROS 1 and ROS 2 alike) into a GnssSample, with the checks both bag
// readers apply. A no-fix message (status -1) is kept, so that ingest and refine can count
// it: drivers fill its position with NaN. Altitude may be NaN (the message's "no altitude").
#pragma once

#include <array>
#include <string>

#include "core/time.h"
#include "worker/io/stream_samples.h"

namespace keel::io {

struct NavSatFixValues {
  int status = 0;
  double latitude_deg = 0.0, longitude_deg = 0.0, altitude_m = 0.0;
  std::array<double, 9> position_covariance{};
  int position_covariance_type = 0;  // 0 COVARIANCE_TYPE_UNKNOWN .. 3 KNOWN
};

// Fails (IoError naming `what` and the field) on a status outside -1..2, a fix whose latitude
// or longitude is not finite or out of range, an unknown covariance type or a covariance with
// a non-finite entry or a negative variance.
GnssSample gnss_sample_of(const NavSatFixValues& fix, TimeNs t_ns, const std::string& what);

}  // namespace keel::io
