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

// The slerp of one knot segment, q(s) = q0 * Exp(s * angle * axis), in the form a point's
// rotation needs: R0 and the segment's rotation as axis and angle (the shorter arc, as
// Eigen's slerp takes). Eigen's slerp spends an acos and two sines on every call; here the
// acos is paid once per segment and each point needs the sine and cosine of a small angle.
struct SegmentSlerp {
  Eigen::Matrix3d R0;
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  double angle_rad = 0.0;

  SegmentSlerp(const Eigen::Quaterniond& q0, const Eigen::Quaterniond& q1) : R0(q0) {
    Eigen::Quaterniond d = q0.conjugate() * q1;
    if (d.w() < 0.0) d.coeffs() = -d.coeffs();
    const double sin_half = d.vec().norm();
    angle_rad = 2.0 * std::atan2(sin_half, d.w());
    if (sin_half > 0.0) axis = d.vec() / sin_half;
  }

  // R(s) * p.
  Eigen::Vector3d rotate(double s, const Eigen::Vector3d& p) const {
    const double half = 0.5 * s * angle_rad;
    double sin_half, cos_half;
    if (std::abs(half) < 0.1) {
      // Taylor series to the term below double precision at |x| < 0.1 (x^9/9! ~ 3e-15 x):
      // knots are trajectory stamps, a few milliseconds apart, so this is the usual case.
      const double x2 = half * half;
      sin_half =
          half * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0))));
      cos_half = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    } else {
      sin_half = std::sin(half);
      cos_half = std::cos(half);
    }
    // Unit quaternion (cos_half, v) applied to p: p + 2 cos_half (v x p) + 2 v x (v x p).
    const Eigen::Vector3d v = sin_half * axis;
    const Eigen::Vector3d vxp = v.cross(p);
    return R0 * (p + 2.0 * cos_half * vxp + 2.0 * v.cross(vxp));
  }
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
  if (knots.t_s.size() == 1) {
    const Pose3 T_ref_sensor = make_pose(knots.q_ref_body[0], knots.t_ref_body[0]) * T_body_sensor;
    for (auto& p : scan.xyz) p = (T_ref_sensor * p.cast<double>()).cast<float>();
    return T_world_sensor_ref;
  }
  std::vector<SegmentSlerp> slerps;
  for (size_t i = 0; i + 1 < knots.t_s.size(); ++i)
    slerps.emplace_back(knots.q_ref_body[i], knots.q_ref_body[i + 1]);
  const size_t last_segment = slerps.size() - 1;
  size_t segment = 0;
  for (size_t k = 0; k < scan.xyz.size(); ++k) {
    const double t = scan.time_s[k];
    // Points usually come in time order: walk from the previous point's segment.
    while (segment < last_segment && t > knots.t_s[segment + 1]) ++segment;
    while (segment > 0 && t < knots.t_s[segment]) --segment;
    const Eigen::Vector3d p_body = T_body_sensor * scan.xyz[k].cast<double>();
    const double dt = knots.t_s[segment + 1] - knots.t_s[segment];
    const double s = std::clamp((t - knots.t_s[segment]) / dt, 0.0, 1.0);
    const Eigen::Vector3d translation =
        (1.0 - s) * knots.t_ref_body[segment] + s * knots.t_ref_body[segment + 1];
    scan.xyz[k] = (slerps[segment].rotate(s, p_body) + translation).cast<float>();
  }
  return T_world_sensor_ref;
}

}  // namespace keel::mapping
