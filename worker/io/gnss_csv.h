// GNSS fixes as a stream CSV (docs/mission-format.md "Stream CSV files"):
// `t,latitude,longitude,height,status[,sigma_e,sigma_n,sigma_u]`: s, degrees (WGS 84), m above
// the ellipsoid, NavSatStatus (-1 no fix, 0 fix, 1 SBAS, 2 GBAS); optional 1-sigma east, north,
// up in m (the fix's covariance is then their squares on the diagonal). A no-fix row may carry
// `nan` coordinates; `nan` sigmas mean "unknown" (the sensor's noise figures apply).
#pragma once

#include <filesystem>

#include "worker/io/stream_samples.h"

namespace keel::io {

// Fails naming file, line and column on a wrong header, a bad number, a status outside
// -1..2, a fix outside the WGS 84 ranges, a negative sigma, or a duplicate/decreasing stamp.
GnssSeries read_gnss_csv(const std::filesystem::path& path);
// Writes the sigma columns when `with_sigmas` (sqrt of the covariance diagonal; nan when the
// sample's covariance is unknown).
void write_gnss_csv(const std::filesystem::path& path, const GnssSeries& samples,
                    bool with_sigmas = false);

}  // namespace keel::io
