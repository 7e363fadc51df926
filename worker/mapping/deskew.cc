#include "worker/mapping/deskew.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace keel::mapping {
namespace {

// Body poses at the sweep's knots, expressed relative to the sensor pose at the scan stamp.
struct Knots {
  std::vector<double> t_s;  // relative to the scan stamp
  std::vector<Eigen::Quaterniond> q_ref_body;
  std::vector<Eigen::Vector3d> t_ref_body;
};

std::string describe_scan(const std::string& sensor, const PointCloud& scan) {
  return "scan of sensor '" + sensor + "' at t=" + format_seconds(scan.t_ns) + " s";
}

void sweep_time_range(const std::string& sensor, const PointCloud& scan,
                      const DeskewOptions& options, double* t_min_s, double* t_max_s) {
  if (scan.time_s.size() != scan.xyz.size()) {
    throw std::invalid_argument(describe_scan(sensor, scan) + ": " +
                                std::to_string(scan.time_s.size()) + " point times for " +
                                std::to_string(scan.xyz.size()) + " points");
  }
  *t_min_s = scan.time_s.front();
  *t_max_s = scan.time_s.front();
  for (size_t k = 0; k < scan.time_s.size(); ++k) {
    const float t = scan.time_s[k];
    if (!std::isfinite(t)) {
      throw std::invalid_argument(describe_scan(sensor, scan) + ": point " + std::to_string(k) +
                                  " has a non-finite time");
    }
    *t_min_s = std::min<double>(*t_min_s, t);
    *t_max_s = std::max<double>(*t_max_s, t);
  }
  if (*t_max_s - *t_min_s > options.max_sweep_duration_s) {
    throw std::invalid_argument(
        describe_scan(sensor, scan) + ": per-point times span " +
        std::to_string(*t_max_s - *t_min_s) +
        " s, more than max_sweep_duration_s = " + std::to_string(options.max_sweep_duration_s) +
        " s; expected seconds relative to the scan stamp (nanoseconds read as seconds?)");
  }
}

Knots make_knots(const TransformTree& tree, const Pose3& T_ref_world, TimeNs t_scan_ns,
                 TimeNs t_first_ns, TimeNs t_last_ns) {
  std::vector<TimeNs> knot_ns{t_first_ns};
  const std::vector<TimeNs>& stamps = tree.body_poses().stamps();
  for (auto it = std::upper_bound(stamps.begin(), stamps.end(), t_first_ns);
       it != stamps.end() && *it < t_last_ns; ++it) {
    knot_ns.push_back(*it);
  }
  if (t_last_ns > t_first_ns) knot_ns.push_back(t_last_ns);

  Knots knots;
  for (const TimeNs t_ns : knot_ns) {
    const Pose3 T_ref_body = T_ref_world * tree.T_world_body(t_ns);  // throws outside
    knots.t_s.push_back(ns_to_seconds(t_ns - t_scan_ns));
    knots.q_ref_body.emplace_back(Eigen::Quaterniond(T_ref_body.linear()).normalized());
    knots.t_ref_body.push_back(T_ref_body.translation());
  }
  return knots;
}

}  // namespace

Pose3 deskew_scan(const TransformTree& tree, const std::string& sensor, PointCloud& scan,
                  const DeskewOptions& options) {
  const Pose3 T_world_sensor_ref = tree.T_world_sensor(sensor, scan.t_ns);
  if (!scan.has_time() || scan.empty()) return T_world_sensor_ref;

  double t_min_s = 0.0, t_max_s = 0.0;
  sweep_time_range(sensor, scan, options, &t_min_s, &t_max_s);
  // Knot span covers every point time (floor/ceil to whole nanoseconds).
  const TimeNs t_first_ns = scan.t_ns + static_cast<TimeNs>(std::floor(t_min_s * 1e9));
  const TimeNs t_last_ns = scan.t_ns + static_cast<TimeNs>(std::ceil(t_max_s * 1e9));
  const Knots knots =
      make_knots(tree, T_world_sensor_ref.inverse(), scan.t_ns, t_first_ns, t_last_ns);

  const Pose3 T_body_sensor = tree.T_body_sensor(sensor);
  const size_t last_segment = knots.t_s.size() >= 2 ? knots.t_s.size() - 2 : 0;
  size_t segment = 0;
  for (size_t k = 0; k < scan.xyz.size(); ++k) {
    const double t = scan.time_s[k];
    // Points usually come in time order: walk from the previous point's segment.
    while (segment < last_segment && t > knots.t_s[segment + 1]) ++segment;
    while (segment > 0 && t < knots.t_s[segment]) --segment;
    const Eigen::Vector3d p_body = T_body_sensor * scan.xyz[k].cast<double>();
    Eigen::Vector3d p_ref;
    if (knots.t_s.size() == 1) {
      p_ref = knots.q_ref_body[0] * p_body + knots.t_ref_body[0];
    } else {
      const double dt = knots.t_s[segment + 1] - knots.t_s[segment];
      const double s = std::clamp((t - knots.t_s[segment]) / dt, 0.0, 1.0);
      const Eigen::Quaterniond q =
          knots.q_ref_body[segment].slerp(s, knots.q_ref_body[segment + 1]);
      const Eigen::Vector3d translation =
          (1.0 - s) * knots.t_ref_body[segment] + s * knots.t_ref_body[segment + 1];
      p_ref = q * p_body + translation;
    }
    scan.xyz[k] = p_ref.cast<float>();
  }
  return T_world_sensor_ref;
}

}  // namespace keel::mapping
