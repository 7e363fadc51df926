#include "worker/io/bag/nav_sat_fix.h"

#include <cmath>

#include "worker/io/io_error.h"

namespace keel::io {

GnssSample gnss_sample_of(const NavSatFixValues& fix, TimeNs t_ns, const std::string& what) {
  GnssSample s;
  s.t_ns = t_ns;
  if (fix.status < -1 || fix.status > 2)
    throw IoError(what + ": status.status is " + std::to_string(fix.status) +
                  ", expected -1 (no fix), 0 (fix), 1 (SBAS) or 2 (GBAS)");
  s.status = fix.status;
  s.latitude_deg = fix.latitude_deg;
  s.longitude_deg = fix.longitude_deg;
  s.height_m = fix.altitude_m;
  if (s.status >= 0) {
    if (!std::isfinite(fix.latitude_deg) || std::abs(fix.latitude_deg) > 90.0)
      throw IoError(what + ": latitude " + std::to_string(fix.latitude_deg) +
                    " of a fix is not in [-90, 90]");
    if (!std::isfinite(fix.longitude_deg) || std::abs(fix.longitude_deg) > 180.0)
      throw IoError(what + ": longitude " + std::to_string(fix.longitude_deg) +
                    " of a fix is not in [-180, 180]");
    if (std::isinf(fix.altitude_m)) throw IoError(what + ": altitude is infinite");
  }
  if (fix.position_covariance_type < 0 || fix.position_covariance_type > 3)
    throw IoError(what + ": position_covariance_type is " +
                  std::to_string(fix.position_covariance_type) + ", expected 0..3");
  s.covariance_known = fix.position_covariance_type != 0 && s.status >= 0;
  if (s.covariance_known) {
    for (size_t i = 0; i < 9; ++i)
      if (!std::isfinite(fix.position_covariance[i]))
        throw IoError(what + ": position_covariance[" + std::to_string(i) + "] is not finite");
    for (size_t i = 0; i < 3; ++i)
      if (fix.position_covariance[4 * i] < 0.0)
        throw IoError(what + ": position_covariance[" + std::to_string(4 * i) +
                      "] is a negative variance");
    s.covariance_enu_m2 = fix.position_covariance;
  }
  return s;
}

}  // namespace keel::io
