#include "worker/stages/ingest/mission_report.h"

#include <algorithm>
#include <cmath>

namespace keel::pipeline {

using nlohmann::json;

json stamp_report(const std::vector<TimeNs>& stamps, double nominal_rate_hz,
                  const IngestOptions& options, const std::string& name, json& warnings) {
  json r = {{"count", stamps.size()}};
  if (stamps.empty()) {
    warnings.push_back(name + ": no data");
    return r;
  }
  const double duration_s = ns_to_seconds(stamps.back() - stamps.front());
  r["t_first_s"] = ns_to_seconds(stamps.front());
  r["t_last_s"] = ns_to_seconds(stamps.back());
  r["duration_s"] = duration_s;
  const double measured =
      duration_s > 0.0 ? static_cast<double>(stamps.size() - 1) / duration_s : 0.0;
  r["rate_hz_measured"] = measured;
  if (nominal_rate_hz > 0.0) {
    r["rate_hz_nominal"] = nominal_rate_hz;
    const double threshold_s = options.gap_factor / nominal_rate_hz;
    size_t gaps = 0;
    double longest_s = 0.0;
    for (size_t i = 1; i < stamps.size(); ++i) {
      const double dt = ns_to_seconds(stamps[i] - stamps[i - 1]);
      if (dt > threshold_s) ++gaps;
      longest_s = std::max(longest_s, dt);
    }
    r["gaps"] = {{"threshold_s", threshold_s}, {"count", gaps}, {"longest_interval_s", longest_s}};
    if (stamps.size() > 1 &&
        std::abs(measured - nominal_rate_hz) > options.rate_tolerance * nominal_rate_hz)
      warnings.push_back(name + ": measured rate " + std::to_string(measured) + " Hz, nominal " +
                         std::to_string(nominal_rate_hz) + " Hz");
    if (gaps > 0)
      warnings.push_back(name + ": " + std::to_string(gaps) + " gaps longer than " +
                         std::to_string(threshold_s) + " s (longest " + std::to_string(longest_s) +
                         " s)");
  }
  return r;
}

}  // namespace keel::pipeline
