#include "tests/worker/slam/synthetic_mission.h"

#include <cmath>
#include <random>

#include "worker/slam/so3.h"

namespace keel::slam::testing {
namespace {

constexpr TimeNs kStart = 1'700'000'000'000'000'000;  // an epoch-like origin

TimeNs stamp(double t_s) { return kStart + seconds_to_ns(t_s); }

Eigen::Matrix3d rot_zyx(double yaw, double pitch, double roll) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// Body rate and specific force of frame `T_body_frame` rigidly attached to the body, and the
// velocity of its origin in its own axes, by central differences of the analytic pose.
struct Kinematics {
  Eigen::Vector3d omega, specific_force, velocity;
};

Kinematics kinematics(double t, double omega_path, const Pose3& T_body_frame, double g) {
  auto pose = [&](double s) { return synthetic_body_pose(s, omega_path) * T_body_frame; };
  const double h = 1e-4;
  const Pose3 T0 = pose(t), Tm = pose(t - h), Tp = pose(t + h);
  Kinematics k;
  k.omega = so3_log(Tm.linear().transpose() * Tp.linear()) / (2 * h);
  const Eigen::Vector3d v_w = (Tp.translation() - Tm.translation()) / (2 * h);
  const Eigen::Vector3d a_w =
      (Tp.translation() - 2 * T0.translation() + Tm.translation()) / (h * h);
  k.specific_force = T0.linear().transpose() * (a_w - Eigen::Vector3d(0, 0, -g));
  k.velocity = T0.linear().transpose() * v_w;
  return k;
}

Eigen::Vector3d gaussian3(std::mt19937_64& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return {n(rng), n(rng), n(rng)};
}

}  // namespace

Pose3 synthetic_body_pose(double t, double w) {
  // Figure-eight with heave; heading along the velocity; roll and pitch from waves.
  const Eigen::Vector3d p(25.0 * std::sin(w * t), 12.0 * std::sin(2 * w * t),
                          0.2 * std::sin(0.7 * t));
  const double vx = 25.0 * w * std::cos(w * t), vy = 24.0 * w * std::cos(2 * w * t);
  const double yaw = std::atan2(vy, vx);
  const double roll = 0.035 * std::sin(1.9 * t), pitch = 0.025 * std::sin(1.3 * t + 0.4);
  return make_pose(Eigen::Quaterniond(rot_zyx(yaw, pitch, roll)), p);
}

SyntheticMission make_synthetic_mission(const SyntheticMissionOptions& o) {
  SyntheticMission m;
  std::mt19937_64 rng(o.seed);
  const double g = 9.81;
  RefineInput& in = m.input;
  in.T_body_imu = o.T_body_imu;
  in.T_body_dvl = o.T_body_dvl_nominal;

  // IMU, Eq. (4)-(5) discretised: noise sigma = density / sqrt(dt).
  const double dt_imu = 1.0 / o.imu_rate_hz;
  const int n_imu = static_cast<int>(o.duration_s * o.imu_rate_hz) + 1;
  for (int k = 0; k < n_imu; ++k) {
    const double t = k * dt_imu;
    const Kinematics kin = kinematics(t, o.path_omega_radps, o.T_body_imu, g);
    ImuSample s;
    s.t_ns = stamp(t);
    s.gyro_radps = kin.omega + o.gyro_bias_radps +
                   gaussian3(rng, o.imu_noise.gyro_noise_density / std::sqrt(dt_imu));
    s.accel_mps2 = kin.specific_force + o.accel_bias_mps2 +
                   gaussian3(rng, o.imu_noise.accel_noise_density / std::sqrt(dt_imu));
    in.imu.push_back(s);
  }

  // DVL, Eq. (8): v~ = s_d v + b^v + eta^v, in the true DVL frame.
  const int n_dvl = static_cast<int>(o.duration_s * o.dvl_rate_hz) + 1;
  for (int k = 0; k < n_dvl; ++k) {
    const double t = k / o.dvl_rate_hz;
    const Kinematics kin = kinematics(t, o.path_omega_radps, o.T_body_dvl_true, g);
    DvlSample d;
    d.t_ns = stamp(t);
    d.velocity_mps = o.dvl_scale * kin.velocity + o.dvl_bias_mps +
                     gaussian3(rng, o.dvl_noise.velocity_sigma(kin.velocity.norm()));
    d.valid = !(o.dvl_dropout_start_s >= 0 && t >= o.dvl_dropout_start_s &&
                t < o.dvl_dropout_start_s + o.dvl_dropout_duration_s);
    if (!d.valid) d.velocity_mps.setConstant(std::nan(""));
    in.dvl.push_back(d);
  }

  // Keyframes, ground truth and the drifting odometry chain.
  const int n_kf = static_cast<int>(o.duration_s / o.keyframe_period_s) + 1;
  Pose3 T_odom = synthetic_body_pose(0.0, o.path_omega_radps);
  for (int k = 0; k < n_kf; ++k) {
    const double t = std::min(k * o.keyframe_period_s, o.duration_s);
    const Pose3 T_true = synthetic_body_pose(t, o.path_omega_radps);
    const bool degenerate = o.degenerate_start_s >= 0 && t > o.degenerate_start_s &&
                            t <= o.degenerate_start_s + o.degenerate_duration_s;
    m.degenerate_truth.push_back(degenerate);
    if (k > 0) {
      const double t_prev = ns_to_seconds(m.ground_truth.back().t_ns - kStart);
      const Pose3 T_prev = synthetic_body_pose(t_prev, o.path_omega_radps);
      const Pose3 d = T_prev.inverse() * T_true;
      RelativePoseMeasurement e;
      e.t_i_ns = stamp(t_prev);
      e.t_j_ns = stamp(t);
      Eigen::Vector3d dt_noise = gaussian3(rng, o.odom_sigma_translation_m);
      Eigen::Vector3d dphi = gaussian3(rng, o.odom_sigma_rotation_rad);
      dphi.z() += o.odom_yaw_drift_radps * (t - t_prev);
      Eigen::Vector3d trans = d.translation() + dt_noise;
      e.information = Matrix6d::Zero();
      e.information.diagonal().head<3>().setConstant(
          1.0 / (o.odom_sigma_translation_m * o.odom_sigma_translation_m));
      e.information.diagonal().tail<3>().setConstant(
          1.0 / (o.odom_sigma_rotation_rad * o.odom_sigma_rotation_rad));
      if (degenerate) {  // the corridor: motion along body x is barely seen
        trans.x() = o.degenerate_x_fraction * d.translation().x() + dt_noise.x();
        e.information(0, 0) = o.degenerate_x_information;
      }
      e.T_i_j = make_pose(Eigen::Quaterniond(d.linear() * so3_exp(dphi)), trans);
      in.odometry.push_back(e);
      T_odom = T_odom * e.T_i_j;
    }
    m.ground_truth.push_back({stamp(t), T_true});
    m.odometry.push_back({stamp(t), T_odom});
  }
  in.keyframes = m.odometry;

  if (o.loop_closures) {
    for (int j = 0; j < n_kf; ++j) {
      for (int i = 0; i < j; ++i) {
        const double gap = ns_to_seconds(m.ground_truth[j].t_ns - m.ground_truth[i].t_ns);
        const Pose3& Ti = m.ground_truth[i].T_world_body;
        const Pose3& Tj = m.ground_truth[j].T_world_body;
        if (gap < o.loop_min_gap_s ||
            (Ti.translation() - Tj.translation()).norm() > o.loop_max_distance_m) {
          continue;
        }
        RelativePoseMeasurement e;
        e.t_i_ns = m.ground_truth[i].t_ns;
        e.t_j_ns = m.ground_truth[j].t_ns;
        const Pose3 d = Ti.inverse() * Tj;
        e.T_i_j = make_pose(
            Eigen::Quaterniond(d.linear() * so3_exp(gaussian3(rng, o.loop_sigma_rotation_rad))),
            d.translation() + gaussian3(rng, o.loop_sigma_translation_m));
        e.information = Matrix6d::Zero();
        e.information.diagonal().head<3>().setConstant(
            1.0 / (o.loop_sigma_translation_m * o.loop_sigma_translation_m));
        e.information.diagonal().tail<3>().setConstant(
            1.0 / (o.loop_sigma_rotation_rad * o.loop_sigma_rotation_rad));
        in.loop_closures.push_back(e);
        break;  // one closure per revisiting keyframe
      }
    }
  }
  return m;
}

}  // namespace keel::slam::testing
