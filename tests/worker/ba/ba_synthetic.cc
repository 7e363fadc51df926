#include "tests/worker/ba/ba_synthetic.h"

#include <Eigen/Geometry>

#include <cmath>
#include <random>

#include "core/mesh_query.h"
#include "worker/ba/rig_geometry.h"

namespace keel::testing {
namespace {

using keel::MeshQuery;

double hull_z(const SyntheticHullOptions& o, double x, double y) {
  return o.curvature_x * x * x + o.curvature_y * y * y;
}

double bump(const SyntheticHullOptions& o, double x, double y) {
  const double r = (Eigen::Vector2d(x, y) - o.bump_center).norm();
  if (r <= o.bump_radius_m) return o.bump_height_m;
  if (r >= o.bump_radius_m + o.bump_falloff_m) return 0.0;
  return o.bump_height_m * 0.5 * (1.0 + std::cos(M_PI * (r - o.bump_radius_m) / o.bump_falloff_m));
}

// Real surface point (model frame): the bump moves the hull toward the water (-z).
Eigen::Vector3d surface_point(const SyntheticHullOptions& o, double x, double y, bool with_bump) {
  return {x, y, hull_z(o, x, y) - (with_bump ? bump(o, x, y) : 0.0)};
}

Pose3 rotation_pose(const Eigen::Vector3d& rotation_vector, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  if (rotation_vector.norm() > 0) {
    T.linear() =
        Eigen::AngleAxisd(rotation_vector.norm(), rotation_vector.normalized()).toRotationMatrix();
  }
  T.translation() = t;
  return T;
}

struct Noise {
  std::mt19937 rng;
  std::normal_distribution<double> unit{0.0, 1.0};
  double operator()(double sigma) { return sigma * unit(rng); }
  Eigen::Vector3d vec(double sigma) { return {(*this)(sigma), (*this)(sigma), (*this)(sigma)}; }
};

keel::ba::BaRig make_rig(const SyntheticHullOptions& o) {
  keel::ba::BaRig rig;
  rig.camera_top = o.camera;
  if (o.stereo) {
    rig.camera_bottom = o.camera;
    rig.T_top_bottom.translation() = Eigen::Vector3d(0, o.stereo_baseline_m, 0);  // vertical pair
  }
  // Vehicle: x forward, y left, z up; the tray pitches about y and looks up at the hull.
  rig.T_vehicle_servo_zero.translation() = Eigen::Vector3d(0.4, 0.0, 0.2);
  rig.servo_axis = Eigen::Vector3d::UnitY();
  rig.T_servo_dvl.translation() = Eigen::Vector3d(-0.1, 0.0, 0.1);
  return rig;
}

// Four Janus beams 30 degrees off the DVL's +z, at azimuths 45 + 90 k.
std::vector<Eigen::Vector3d> janus_beams() {
  std::vector<Eigen::Vector3d> beams;
  const double tilt = 30.0 * M_PI / 180.0;
  for (int k = 0; k < 4; ++k) {
    const double az = (45.0 + 90.0 * k) * M_PI / 180.0;
    beams.emplace_back(std::sin(tilt) * std::cos(az), std::sin(tilt) * std::sin(az),
                       std::cos(tilt));
  }
  return beams;
}

void add_keyframes(const SyntheticHullOptions& o, Noise& noise, SyntheticHull& out) {
  std::vector<Pose3> T_model_vehicle;
  std::vector<double> times;
  double t = 0;
  for (int lane = 0; lane < o.lanes; ++lane) {
    const double y = (lane - 0.5 * (o.lanes - 1)) * o.lane_spacing_m;
    const bool forward = lane % 2 == 0;
    const int n = static_cast<int>(std::floor(2 * o.lane_half_length_m / o.keyframe_spacing_m)) + 1;
    for (int i = 0; i < n; ++i) {
      const double s = -o.lane_half_length_m + i * o.keyframe_spacing_m;
      const double x = forward ? s : -s;
      const Eigen::Vector3d p(x, y, hull_z(o, x, y) - o.standoff_m);
      if (!T_model_vehicle.empty()) {
        t += (p - T_model_vehicle.back().translation()).norm() / o.speed_m_per_s;
      }
      T_model_vehicle.push_back(rotation_pose(Eigen::Vector3d(0, 0, forward ? 0.0 : M_PI), p));
      times.push_back(t);
    }
  }
  for (size_t i = 0; i < T_model_vehicle.size(); ++i) {
    out.T_world_vehicle.push_back(out.T_world_model * T_model_vehicle[i]);
    out.servo_angle_rad.push_back(0.03 * std::sin(0.7 * i));  // the tray's true motion
    keel::ba::BaKeyframe k;
    k.t_ns = static_cast<TimeNs>(std::llround(times[i] * 1e9)) + 1'000'000'000;
    k.servo_angle_rad = out.servo_angle_rad[i] + noise(o.servo_slop_rad);
    const keel::ba::DepthPitchRoll truth = keel::ba::DepthPitchRoll{
        out.T_world_vehicle[i].translation().z(),
        std::atan2(-out.T_world_vehicle[i].linear()(2, 0),
                   std::hypot(out.T_world_vehicle[i].linear()(2, 1),
                              out.T_world_vehicle[i].linear()(2, 2))),
        std::atan2(out.T_world_vehicle[i].linear()(2, 1), out.T_world_vehicle[i].linear()(2, 2))};
    k.depth_pitch_roll = keel::ba::DepthPitchRoll{truth.z_world_m + noise(o.depth_noise_m),
                                                  truth.pitch_rad + noise(o.attitude_noise_rad),
                                                  truth.roll_rad + noise(o.attitude_noise_rad)};
    out.problem.keyframes.push_back(k);
  }
  // Dead-reckoning odometry between consecutive keyframes (Eq. 11's measurements).
  auto& kf = out.problem.keyframes;
  for (size_t i = 1; i < kf.size(); ++i) {
    const double dt = ns_to_seconds(kf[i].t_ns - kf[i - 1].t_ns);
    const Pose3 truth = out.T_world_vehicle[i - 1].inverse() * out.T_world_vehicle[i];
    const Pose3 measured = truth * rotation_pose(noise.vec(o.odometry_noise_rad_per_s * dt),
                                                 noise.vec(o.odometry_noise_m_per_s * dt));
    out.problem.odometry.push_back({static_cast<int>(i - 1), static_cast<int>(i), measured});
  }
  // SLAM-corrected initial poses: a drifting error on top of the truth.
  Pose3 error = Pose3::Identity();
  for (size_t i = 0; i < kf.size(); ++i) {
    if (i > 0) {
      error = error *
              rotation_pose(noise.vec(o.initial_pose_drift_rad), noise.vec(o.initial_pose_drift_m));
    }
    kf[i].T_world_vehicle = out.T_world_vehicle[i] * error;
  }
}

void add_landmarks(const SyntheticHullOptions& o, Noise& noise, SyntheticHull& out) {
  const double x_extent = o.lane_half_length_m + 0.4;
  const double y_extent = 0.5 * (o.lanes - 1) * o.lane_spacing_m + 0.3;
  std::uniform_real_distribution<double> ux(-x_extent, x_extent), uy(-y_extent, y_extent);
  std::uniform_real_distribution<double> ur(0.0, 1.0);
  const MeshQuery cad(make_hull_patch(o, false));
  for (int i = 0; i < o.landmarks + o.bump_landmarks; ++i) {
    double x, y;
    if (i < o.landmarks) {
      x = ux(noise.rng);
      y = uy(noise.rng);
    } else {  // uniform on the bump's flat top
      const double r = 0.95 * o.bump_radius_m * std::sqrt(ur(noise.rng));
      const double a = 2 * M_PI * ur(noise.rng);
      x = o.bump_center.x() + r * std::cos(a);
      y = o.bump_center.y() + r * std::sin(a);
    }
    const Eigen::Vector3d p_model = surface_point(o, x, y, true);
    out.landmarks_world.push_back(out.T_world_model * p_model);
    out.landmark_height_m.push_back(cad.signed_distance(p_model));
  }
}

void add_observations(const SyntheticHullOptions& o, Noise& noise, SyntheticHull& out) {
  const keel::ba::ServoMount mount = keel::ba::servo_mount(out.problem.rig);
  const auto in_image = [&](const Eigen::Vector3d& p_c, Eigen::Vector2d& uv) {
    if (p_c.z() < 0.2) return false;
    uv = keel::ba::project(o.camera, p_c);
    return uv.x() >= 5 && uv.y() >= 5 && uv.x() < o.camera.width - 5 &&
           uv.y() < o.camera.height - 5;
  };
  const Pose3 T_bottom_top = out.problem.rig.T_top_bottom.inverse();
  std::vector<Pose3> T_camera_world;
  for (size_t i = 0; i < out.T_world_vehicle.size(); ++i) {
    T_camera_world.push_back(keel::ba::world_camera_pose(out.T_world_vehicle[i],
                                                         out.servo_angle_rad[i], mount,
                                                         out.T_servo_camera)
                                 .inverse());
  }
  for (size_t l = 0; l < out.landmarks_world.size(); ++l) {
    keel::ba::FeatureTrack track;
    track.landmark_id = static_cast<int64_t>(l);
    for (size_t i = 0; i < T_camera_world.size(); ++i) {
      const Eigen::Vector3d p_c = T_camera_world[i] * out.landmarks_world[l];
      Eigen::Vector2d uv, uv_bottom;
      if (!in_image(p_c, uv)) continue;
      keel::ba::FeatureObservation obs;
      obs.keyframe = static_cast<int>(i);
      obs.pixel = uv + Eigen::Vector2d(noise(o.pixel_noise), noise(o.pixel_noise));
      if (o.stereo) {
        if (!in_image(T_bottom_top * p_c, uv_bottom)) continue;
        obs.pixel_bottom = uv_bottom + Eigen::Vector2d(noise(o.pixel_noise), noise(o.pixel_noise));
      }
      track.observations.push_back(obs);
    }
    if (track.observations.size() >= 2) out.problem.tracks.push_back(std::move(track));
  }
}

void add_dvl(const SyntheticHullOptions& o, Noise& noise, SyntheticHull& out) {
  const MeshQuery real(out.real_surface_model);
  const keel::ba::ServoMount mount = keel::ba::servo_mount(out.problem.rig);
  const Pose3 T_model_world = out.T_world_model.inverse();
  const auto beams = janus_beams();
  for (size_t i = 0; i < out.T_world_vehicle.size(); ++i) {
    const Pose3 T_model_dvl = T_model_world * out.T_world_vehicle[i] *
                              mount.T_vehicle_servo(out.servo_angle_rad[i]) *
                              out.problem.rig.T_servo_dvl;
    for (size_t b = 0; b < beams.size(); ++b) {
      keel::Ray ray;
      ray.origin = T_model_dvl.translation();
      ray.direction = T_model_dvl.linear() * beams[b];
      ray.max_range_m = 10;
      const auto hit = real.raycast(ray);
      if (!hit) continue;
      out.problem.dvl_ranges.push_back({static_cast<int>(i), static_cast<int>(b), beams[b],
                                        hit->distance_m + noise(o.dvl_noise_m)});
    }
  }
}

}  // namespace

TriangleMesh make_hull_patch(const SyntheticHullOptions& o, bool with_bump) {
  TriangleMesh mesh;
  const int nx = static_cast<int>(std::round(2 * o.half_length_m / o.grid_m));
  const int ny = static_cast<int>(std::round(2 * o.half_width_m / o.grid_m));
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      mesh.vertices.push_back(surface_point(o, -o.half_length_m + i * o.grid_m,
                                            -o.half_width_m + j * o.grid_m, with_bump));
    }
  }
  const auto v = [nx](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      // Clockwise seen from +z: outward normals point down, to the water.
      mesh.faces.emplace_back(v(i, j), v(i + 1, j + 1), v(i + 1, j));
      mesh.faces.emplace_back(v(i, j), v(i, j + 1), v(i + 1, j + 1));
    }
  }
  return mesh;
}

SyntheticHull make_synthetic_hull(const SyntheticHullOptions& o) {
  SyntheticHull out;
  Noise noise{std::mt19937(o.seed)};
  out.T_world_model =
      rotation_pose(Eigen::Vector3d(0.02, -0.03, 0.05), Eigen::Vector3d(3.0, -2.0, -4.0));
  out.T_servo_camera = rotation_pose(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.1, 0.0, 0.1));
  out.real_surface_model = make_hull_patch(o, true);
  out.problem.rig = make_rig(o);
  // The calibration handed to the BA is off by ~2 cm and ~0.6 degrees.
  out.problem.rig.T_servo_camera =
      out.T_servo_camera *
      rotation_pose(o.extrinsic_error_scale * Eigen::Vector3d(0.006, -0.008, 0.004),
                    o.extrinsic_error_scale * Eigen::Vector3d(0.012, -0.01, 0.015));
  out.problem.cad_mesh = make_hull_patch(o, false);
  // The CAD-to-world guess GICP starts from: ~15 cm and ~2 degrees off.
  out.problem.T_world_model_guess =
      out.T_world_model *
      rotation_pose(o.model_guess_error_scale * Eigen::Vector3d(0.02, 0.015, -0.02),
                    o.model_guess_error_scale * Eigen::Vector3d(0.1, -0.08, 0.08));
  add_keyframes(o, noise, out);
  add_landmarks(o, noise, out);
  add_observations(o, noise, out);
  add_dvl(o, noise, out);
  return out;
}

}  // namespace keel::testing
