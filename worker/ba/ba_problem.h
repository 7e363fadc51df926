// Input of model-assisted bundle adjustment (seed 001, Ozog et al. 2017, Sec. 2).
//
// Frames (seed 001, Fig. 9), all right-handed:
//   world   the common ("global", g) frame of the SLAM keyframe poses. Gravity aligned: its z
//           axis is vertical (up), so Eq. (9) can observe z, pitch and roll directly.
//   vehicle v_i, the body frame of keyframe i; T_world_vehicle is x_gv_i.
//   servo   s_i, the sensor tray. T_vehicle_servo(theta) = T_vehicle_servo_zero * Rot(axis, theta):
//           the instrumented servo angle theta_v_i_s_i rotates the tray about `servo_axis`.
//   camera  c_T, the top (or only) camera; T_servo_camera is the uncertain extrinsic x_sc_T.
//           Pinhole, rectified: x right, y down, z along the optical axis.
//   camera_bottom  c_B, the bottom camera of a rectified stereo pair; T_top_bottom is
//           x_cT_cB from stereo calibration (fixed).
//   dvl     the DVL head on the tray, T_servo_dvl fixed; beams are unit vectors in it.
//   model   M, the CAD mesh frame; T_world_model is x_gM (unknown, Sec. 2.5).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <vector>

#include "core/pose.h"
#include "core/time.h"
#include "core/triangle_mesh.h"

namespace keel::ba {

// 8-bit gray image, row-major, tightly packed (width * height bytes).
struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;
  bool empty() const { return pixels.empty(); }
};

// Rectified pinhole camera (no distortion): u = fx x/z + cx, v = fy y/z + cy.
struct PinholeCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;  // pixels; observations outside are rejected
};

struct BaRig {
  PinholeCamera camera_top;
  // Present for a stereo rig (Eq. 12); absent for a monocular camera (Eq. 13).
  std::optional<PinholeCamera> camera_bottom;
  Pose3 T_top_bottom = Pose3::Identity();          // x_cT_cB: bottom camera in the top camera frame
  Pose3 T_vehicle_servo_zero = Pose3::Identity();  // tray pose at servo angle 0
  Eigen::Vector3d servo_axis = Eigen::Vector3d::UnitY();  // unit, in the servo frame
  Pose3 T_servo_camera = Pose3::Identity();               // initial guess of x_sc_T (refined by BA)
  Pose3 T_servo_dvl = Pose3::Identity();                  // fixed
};

// Depth, pitch and roll observed by the pressure sensor and the IMU (Eq. 9). z_world_m is
// the world z of the vehicle origin (e.g. minus the pressure depth when world z is up);
// roll and pitch are the Z-Y-X Euler angles of R_world_vehicle = Rz(yaw) Ry(pitch) Rx(roll).
struct DepthPitchRoll {
  double z_world_m = 0;
  double pitch_rad = 0;
  double roll_rad = 0;
};

struct BaKeyframe {
  TimeNs t_ns = 0;                            // strictly increasing over keyframes
  Pose3 T_world_vehicle = Pose3::Identity();  // initial guess (SLAM-corrected pose)
  double servo_angle_rad = 0;                 // instrumented servo angle, Eq. (10)
  // Eq. (9) measurement; when absent it is read off the initial pose (which the SLAM
  // estimated from the same depth and IMU data).
  std::optional<DepthPitchRoll> depth_pitch_roll;
  // Images for the frontend; used only when BaProblem::tracks is empty.
  GrayImage image_top;
  GrayImage image_bottom;  // stereo rigs only
};

// Relative-pose odometry between two keyframes (Eq. 11): T_from_to = x_g_from^-1 * x_g_to
// as measured by dead reckoning. Its sigma grows with the keyframes' time difference.
struct BaOdometry {
  int from = 0;
  int to = 0;
  Pose3 T_from_to = Pose3::Identity();
};

// One feature detection. pixel_bottom is set for a stereo observation (Eq. 12); without it
// the observation is monocular (Eq. 13).
struct FeatureObservation {
  int keyframe = 0;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // top camera, pixels
  std::optional<Eigen::Vector2d> pixel_bottom;
};

// A landmark and its detections, at most one per keyframe.
struct FeatureTrack {
  int64_t landmark_id = 0;
  std::vector<FeatureObservation> observations;
};

// One DVL range return (Eq. 14): the beam's unit direction in the DVL frame and the range
// along it, attached to the keyframe whose pose it was taken at.
struct DvlRange {
  int keyframe = 0;
  int beam = 0;  // 0..3 for a four-beam Janus DVL; informational
  Eigen::Vector3d direction_dvl = Eigen::Vector3d::UnitZ();
  double range_m = 0;
};

struct BaProblem {
  std::vector<BaKeyframe> keyframes;
  std::vector<BaOdometry> odometry;
  // Ready-made feature tracks. When empty, the frontend builds them from the keyframe images.
  std::vector<FeatureTrack> tracks;
  std::vector<DvlRange> dvl_ranges;
  BaRig rig;
  TriangleMesh cad_mesh;  // M_prior, outward oriented, in the model frame
  // Starting point of the GICP alignment of Sec. 2.5 (and x_gM's prior when GICP is off).
  Pose3 T_world_model_guess = Pose3::Identity();
};

// Odometry between consecutive keyframes read off their initial poses: what a caller without
// separate dead-reckoning uses (the SLAM poses then double as odometry).
std::vector<BaOdometry> odometry_from_initial_poses(const std::vector<BaKeyframe>& keyframes);

// Throws std::invalid_argument naming the field (e.g. "keyframes[3].t_ns") for anything the
// solver cannot use: unsorted times, odometry or observations indexing missing keyframes,
// non-finite values, non-unit beam directions, an empty mesh, bad intrinsics.
void validate(const BaProblem& problem);

}  // namespace keel::ba
