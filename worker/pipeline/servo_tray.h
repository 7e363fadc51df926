// Sensors on a servo tray (docs/mission-format.md "Servo trays", seed 001 Fig. 9): the tray
// angle at a time, and DVL velocities taken from the turning tray's frame into the frame the
// DVL has at angle 0 (its manifest extrinsic), so that a fusion with a fixed extrinsic
// (refine's DVL preintegration) can use them.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <vector>

#include "proto/mission_manifest.h"
#include "core/pose.h"
#include "core/time.h"
#include "worker/io/stream_samples.h"
#include "worker/slam/sensor_samples.h"

namespace keel::pipeline {

// The servo's rotation axis in its own frame, unit length: the manifest's `axis`, [0, 0, 1]
// when it gives none.
Eigen::Vector3d tray_axis(const proto::SensorSpec& servo);

// The servo angle at t_ns: a least-squares line through the samples within +-half_window_ns,
// evaluated at t_ns. The instrumented angle carries 5 deg noise per sample (seed 001 Eq. 10);
// the tray turns slowly, so a local line through ~20 samples keeps the motion and divides the
// noise by ~sqrt(20). Linear interpolation when fewer than 3 samples fall in the window;
// nullopt outside the series.
std::optional<double> servo_angle_at(const io::ServoSeries& servo, TimeNs t_ns,
                                     TimeNs half_window_ns);

struct TrayDvlStats {
  size_t rotated = 0;        // samples taken into the angle-0 frame
  size_t without_angle = 0;  // outside the servo series: marked invalid (dropouts)
  double max_angle_rad = 0;  // largest |tray angle| applied
};

// Each valid sample's velocity v (in the DVL frame at tray angle theta(t)) becomes
//   R_dvl0_dvl(theta) v,  R_dvl0_dvl(theta) = R_body_dvl0^T Rot(a_body, theta) R_body_dvl0,
// with a_body = R_body_servo * axis_servo: the rotation part of the tray formula. The DVL
// measures its own origin's velocity; that origin must lie on the tray's axis (the tray's turn
// then moves it nowhere and adds no velocity), else std::invalid_argument names the offset.
TrayDvlStats rotate_tray_dvl(std::vector<slam::DvlSample>& samples, const io::ServoSeries& servo,
                             const Pose3& T_body_servo, const Eigen::Vector3d& axis_servo,
                             const Pose3& T_body_dvl0, TimeNs half_window_ns);

}  // namespace keel::pipeline
