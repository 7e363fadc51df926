#include "worker/stages/ba/dvl_returns.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace keel::pipeline {

std::vector<ba::DvlRange> dvl_ranges_at_keyframes(const io::MissionReader& reader,
                                                  const proto::SensorSpec& dvl,
                                                  const std::vector<ba::BaKeyframe>& keyframes,
                                                  double max_dt_s) {
  if (dvl.beams.size() != 4)
    throw std::runtime_error("ba: dvl_ranges sensor '" + dvl.name + "' needs 4 beams");
  const io::DvlRangesSeries series = reader.read_dvl_ranges(dvl.name);
  std::vector<ba::DvlRange> out;
  const TimeNs max_dt_ns = TimeNs(max_dt_s * 1e9);
  for (size_t k = 0; k < keyframes.size(); ++k) {
    const TimeNs t = keyframes[k].t_ns;
    auto it = std::lower_bound(series.begin(), series.end(), t,
                               [](const io::DvlRangesSample& s, TimeNs x) { return s.t_ns < x; });
    const io::DvlRangesSample* best = nullptr;
    if (it != series.end()) best = &*it;
    if (it != series.begin() && (!best || t - (it - 1)->t_ns < best->t_ns - t)) best = &*(it - 1);
    if (!best || std::llabs(best->t_ns - t) > max_dt_ns) continue;
    for (int b = 0; b < 4; ++b) {
      if (!std::isfinite(best->range_m[b])) continue;  // no return
      ba::DvlRange r;
      r.keyframe = int(k);
      r.beam = b;
      r.direction_dvl =
          Eigen::Vector3d(dvl.beams[b][0], dvl.beams[b][1], dvl.beams[b][2]).normalized();
      r.range_m = best->range_m[b];
      out.push_back(r);
    }
  }
  return out;
}

}  // namespace keel::pipeline
