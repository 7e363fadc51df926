// A small simulated hull for the BA tests and benchmark: a gently curved hull patch (the CAD
// mesh, model frame), the real surface = CAD + a flat-topped bump that is NOT in the CAD,
// an HAUV flying lawnmower lanes below it with its sensor tray servoed up at the hull, SIFT-like
// feature tracks of landmarks on the real surface (monocular or stereo, pixel noise), noisy
// dead-reckoning odometry (5 mm/s, 80 deg/h), noisy depth/pitch/roll, servo slop, four-beam
// Janus DVL ranges cast against the real surface, SLAM-corrected initial poses, a miscalibrated
// servo-camera extrinsic and a CAD-to-world misalignment. Everything is generated from a seed;
// ground truth is returned.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "worker/ba/ba_problem.h"

namespace keel::testing {

struct SyntheticHullOptions {
  // Hull patch in the model frame: z = curvature_x x^2 + curvature_y y^2, x, y in +-half
  // extents; the water (outside) is below, outward normals point to -z.
  double half_length_m = 2.5;
  double half_width_m = 1.8;
  double grid_m = 0.05;
  double curvature_x = 0.06;
  double curvature_y = 0.12;
  // Bump toward the vehicle (outside): flat top of `bump_height_m` within bump_radius_m of
  // bump_center, cosine fall-off over bump_falloff_m.
  Eigen::Vector2d bump_center = Eigen::Vector2d(0.2, 0.0);
  double bump_height_m = 0.10;
  double bump_radius_m = 0.22;
  double bump_falloff_m = 0.08;
  // Survey: lanes along x at y = (lane - (lanes-1)/2) * lane_spacing_m.
  int lanes = 3;
  double lane_spacing_m = 0.55;
  double lane_half_length_m = 1.5;
  double keyframe_spacing_m = 0.3;
  double speed_m_per_s = 0.15;
  double standoff_m = 1.5;
  int landmarks = 900;
  int bump_landmarks = 60;  // extra landmarks on the bump's flat top
  bool stereo = false;
  double stereo_baseline_m = 0.1;
  keel::ba::PinholeCamera camera{1000, 1000, 320, 240, 640, 480};
  double pixel_noise = 1.0;
  // Initial poses are the online SLAM's (Sec. 2.5: "SLAM-corrected"): truth with a slowly
  // drifting error, a random walk of these steps per keyframe (the first keyframe exact: it
  // fixes the gauge). Odometry factors get their own dead-reckoning noise below.
  double initial_pose_drift_m = 0.004;
  double initial_pose_drift_rad = 0.03 * 0.017453292519943295;
  // DVL dead reckoning drifts ~0.5 % of distance travelled (1 mm/s at 0.15 m/s); the BA still
  // models it with the paper's conservative 5 mm/s.
  double odometry_noise_m_per_s = 0.001;
  double odometry_noise_rad_per_s = 80.0 * 0.017453292519943295 / 3600.0;
  double depth_noise_m = 0.01;
  double attitude_noise_rad = 0.05 * 0.017453292519943295;
  double servo_slop_rad = 1.0 * 0.017453292519943295;
  double dvl_noise_m = 0.003;
  // Scales of the calibration error handed to the BA (~2 cm, ~0.6 deg) and of the error of
  // the CAD-to-world guess GICP starts from (~15 cm, ~2 deg); 0 = exact.
  double extrinsic_error_scale = 1.0;
  double model_guess_error_scale = 1.0;
  uint32_t seed = 7;
};

struct SyntheticHull {
  keel::ba::BaProblem problem;
  // Ground truth.
  std::vector<Pose3> T_world_vehicle;
  std::vector<double> servo_angle_rad;
  Pose3 T_world_model = Pose3::Identity();
  Pose3 T_servo_camera = Pose3::Identity();
  std::vector<Eigen::Vector3d> landmarks_world;  // index = FeatureTrack::landmark_id
  std::vector<double> landmark_height_m;         // true signed distance to the CAD (bump height)
  TriangleMesh real_surface_model;               // CAD + bump, model frame
};

SyntheticHull make_synthetic_hull(const SyntheticHullOptions& options);

// The hull patch as a triangle grid (model frame), with `bump` added when true.
TriangleMesh make_hull_patch(const SyntheticHullOptions& options, bool bump);

}  // namespace keel::testing
