#include "worker/ba/ba_problem.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace keel::ba {
namespace {

[[noreturn]] void fail(const std::string& field, const std::string& expected) {
  throw std::invalid_argument("ba problem: " + field + ": expected " + expected);
}

std::string at(const std::string& name, size_t i) { return name + "[" + std::to_string(i) + "]"; }

bool finite_pose(const Pose3& T) { return T.matrix().allFinite(); }

bool orthonormal(const Pose3& T) {
  const Eigen::Matrix3d R = T.linear();
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-6 && R.determinant() > 0;
}

void check_pose(const Pose3& T, const std::string& field) {
  if (!finite_pose(T) || !orthonormal(T)) fail(field, "a finite rigid transform");
}

void check_camera(const PinholeCamera& c, const std::string& field) {
  const bool ok = std::isfinite(c.fx) && std::isfinite(c.fy) && std::isfinite(c.cx) &&
                  std::isfinite(c.cy) && c.fx > 0 && c.fy > 0 && c.width > 0 && c.height > 0;
  if (!ok) fail(field, "fx, fy > 0, finite cx, cy and width, height > 0");
}

void check_keyframe_index(int k, size_t n, const std::string& field) {
  if (k < 0 || static_cast<size_t>(k) >= n) {
    fail(field, "a keyframe index in [0, " + std::to_string(n) + "), got " + std::to_string(k));
  }
}

void check_pixel(const Eigen::Vector2d& p, const std::string& field) {
  if (!p.allFinite()) fail(field, "finite pixel coordinates");
}

void validate_rig(const BaRig& rig) {
  check_camera(rig.camera_top, "rig.camera_top");
  if (rig.camera_bottom) check_camera(*rig.camera_bottom, "rig.camera_bottom");
  check_pose(rig.T_top_bottom, "rig.T_top_bottom");
  check_pose(rig.T_vehicle_servo_zero, "rig.T_vehicle_servo_zero");
  check_pose(rig.T_servo_camera, "rig.T_servo_camera");
  check_pose(rig.T_servo_dvl, "rig.T_servo_dvl");
  if (!rig.servo_axis.allFinite() || std::abs(rig.servo_axis.norm() - 1.0) > 1e-6) {
    fail("rig.servo_axis", "a unit vector");
  }
}

void validate_keyframes(const BaProblem& problem) {
  if (problem.keyframes.empty()) fail("keyframes", "at least one keyframe");
  for (size_t i = 0; i < problem.keyframes.size(); ++i) {
    const BaKeyframe& k = problem.keyframes[i];
    if (i > 0 && k.t_ns <= problem.keyframes[i - 1].t_ns) {
      fail(at("keyframes", i) + ".t_ns", "strictly increasing times");
    }
    check_pose(k.T_world_vehicle, at("keyframes", i) + ".T_world_vehicle");
    if (!std::isfinite(k.servo_angle_rad)) fail(at("keyframes", i) + ".servo_angle_rad", "finite");
    if (k.depth_pitch_roll) {
      const DepthPitchRoll& z = *k.depth_pitch_roll;
      if (!std::isfinite(z.z_world_m) || !std::isfinite(z.pitch_rad) ||
          !std::isfinite(z.roll_rad)) {
        fail(at("keyframes", i) + ".depth_pitch_roll", "finite values");
      }
    }
    for (const auto* image : {&k.image_top, &k.image_bottom}) {
      if (!image->empty() && (image->width <= 0 || image->height <= 0 ||
                              image->pixels.size() != size_t(image->width) * image->height)) {
        fail(at("keyframes", i) + (image == &k.image_top ? ".image_top" : ".image_bottom"),
             "width * height bytes of 8-bit gray pixels");
      }
    }
  }
}

void validate_tracks(const BaProblem& problem) {
  const size_t n = problem.keyframes.size();
  std::unordered_set<int64_t> ids;
  for (size_t t = 0; t < problem.tracks.size(); ++t) {
    const FeatureTrack& track = problem.tracks[t];
    if (!ids.insert(track.landmark_id).second) {
      fail(at("tracks", t) + ".landmark_id",
           "unique ids, " + std::to_string(track.landmark_id) + " repeats");
    }
    std::unordered_set<int> seen;
    for (size_t o = 0; o < track.observations.size(); ++o) {
      const FeatureObservation& obs = track.observations[o];
      const std::string field = at(at("tracks", t) + ".observations", o);
      check_keyframe_index(obs.keyframe, n, field + ".keyframe");
      if (!seen.insert(obs.keyframe).second)
        fail(field + ".keyframe", "one observation per keyframe");
      check_pixel(obs.pixel, field + ".pixel");
      if (obs.pixel_bottom) {
        if (!problem.rig.camera_bottom) fail(field + ".pixel_bottom", "a rig.camera_bottom");
        check_pixel(*obs.pixel_bottom, field + ".pixel_bottom");
      }
    }
  }
}

}  // namespace

std::vector<BaOdometry> odometry_from_initial_poses(const std::vector<BaKeyframe>& keyframes) {
  std::vector<BaOdometry> odometry;
  for (size_t i = 1; i < keyframes.size(); ++i) {
    odometry.push_back({static_cast<int>(i - 1), static_cast<int>(i),
                        keyframes[i - 1].T_world_vehicle.inverse() * keyframes[i].T_world_vehicle});
  }
  return odometry;
}

void validate(const BaProblem& problem) {
  validate_rig(problem.rig);
  validate_keyframes(problem);
  const size_t n = problem.keyframes.size();
  for (size_t i = 0; i < problem.odometry.size(); ++i) {
    const BaOdometry& o = problem.odometry[i];
    check_keyframe_index(o.from, n, at("odometry", i) + ".from");
    check_keyframe_index(o.to, n, at("odometry", i) + ".to");
    if (problem.keyframes[o.to].t_ns <= problem.keyframes[o.from].t_ns) {
      fail(at("odometry", i), "a later 'to' keyframe than 'from'");
    }
    check_pose(o.T_from_to, at("odometry", i) + ".T_from_to");
  }
  validate_tracks(problem);
  for (size_t i = 0; i < problem.dvl_ranges.size(); ++i) {
    const DvlRange& r = problem.dvl_ranges[i];
    check_keyframe_index(r.keyframe, n, at("dvl_ranges", i) + ".keyframe");
    if (!r.direction_dvl.allFinite() || std::abs(r.direction_dvl.norm() - 1.0) > 1e-6) {
      fail(at("dvl_ranges", i) + ".direction_dvl", "a unit vector");
    }
    if (!std::isfinite(r.range_m) || r.range_m <= 0) {
      fail(at("dvl_ranges", i) + ".range_m", "a finite range > 0 m");
    }
  }
  if (problem.cad_mesh.faces.empty()) fail("cad_mesh", "a triangle mesh with faces");
  check_pose(problem.T_world_model_guess, "T_world_model_guess");
}

}  // namespace keel::ba
