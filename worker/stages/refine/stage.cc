// Stage `refine`, as numbered steps:
//   1. options (--set refine.x=v) and the mission's sensors: the first IMU, the first DVL;
//   2. keyframes: the recorded `map` poses (stamps and initial values);
//   3. odometry edges L_ij: the recorded `odometry` interpolated at the keyframes, or GICP
//      between keyframe scans of the first lidar when the mission records none;
//   4. loop closures (loops.csv), IMU and DVL samples, extrinsics, noise from mission.yaml;
//   5. the batch solve with DVL fusion (seed 000 Sec. IV) and, when ground truth exists, a
//      second solve without it, so the report can set them side by side (Table II);
//   6. trajectory_refined.tum and the report section (inputs, solver, degeneracy, s_d, the
//      DVL-IMU rotation, DVL gaps, ATE/RPE against ground truth).
#include "worker/stages/refine/stage.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/stage_options.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "proto/contract_error.h"
#include "worker/io/display_path.h"
#include "worker/io/mission_reader.h"
#include "worker/io/tum.h"
#include "worker/io/yaml_json.h"
#include "worker/pipeline/servo_tray.h"
#include "worker/pipeline/trajectories_file.h"
#include "worker/slam/gicp_odometry.h"
#include "worker/slam/map_agreement.h"
#include "worker/slam/so3.h"
#include "worker/slam/trajectory_metrics.h"

namespace keel::pipeline {

namespace {

using nlohmann::json;
using proto::ContractError;
using proto::SensorType;

constexpr double kRadToDeg = 180.0 / M_PI;

// ---- options ------------------------------------------------------------------------------

void local_require(bool ok, const std::string& option, const std::string& expected) {
  if (!ok) throw ContractError("options.refine." + option + ": expected " + expected);
}

// ---- inputs -------------------------------------------------------------------------------

// The sensor named by `chosen`, else the first of `type`; nullptr when the mission has none.
const proto::SensorSpec* pick_sensor(const proto::MissionManifest& manifest,
                                     const std::string& chosen, SensorType type,
                                     const std::string& option) {
  if (!chosen.empty()) {
    const proto::SensorSpec* s = manifest.find_sensor(chosen);
    if (!s)
      throw ContractError("options.refine." + option + ": mission has no sensor '" + chosen + "'");
    if (s->type != type)
      throw ContractError("options.refine." + option + ": sensor '" + chosen + "' is a " +
                          proto::to_string(s->type) + ", expected " + proto::to_string(type));
    return s;
  }
  for (const auto& s : manifest.sensors)
    if (s.type == type) return &s;
  return nullptr;
}

json span_json(TimeNs first, TimeNs last) {
  return {{"t_first_s", ns_to_seconds(first)},
          {"t_last_s", ns_to_seconds(last)},
          {"duration_s", ns_to_seconds(last - first)}};
}

std::vector<slam::ImuSample> to_slam(const io::ImuSeries& series) {
  std::vector<slam::ImuSample> out(series.size());
  for (size_t k = 0; k < series.size(); ++k)
    out[k] = {series[k].t_ns, series[k].gyro_rad_s, series[k].accel_m_s2};
  return out;
}

std::vector<slam::DvlSample> to_slam(const io::DvlSeries& series) {
  std::vector<slam::DvlSample> out(series.size());
  for (size_t k = 0; k < series.size(); ++k)
    out[k] = {series[k].t_ns, series[k].velocity_m_s, series[k].valid};
  return out;
}

// Gaps between consecutive valid DVL samples longer than max_gap_s: Algorithm 1 does not
// bridge them, so no DVL factor spans them.
json dvl_gaps(const std::vector<slam::DvlSample>& dvl, double max_gap_s) {
  size_t gaps = 0, invalid = 0;
  double longest_s = 0.0, total_s = 0.0;
  TimeNs previous = -1;
  bool have_previous = false;
  for (const auto& s : dvl) {
    if (!s.valid) {
      ++invalid;
      continue;
    }
    if (have_previous) {
      const double dt = ns_to_seconds(s.t_ns - previous);
      longest_s = std::max(longest_s, dt);
      if (dt > max_gap_s) {
        ++gaps;
        total_s += dt;
      }
    }
    previous = s.t_ns;
    have_previous = true;
  }
  return {{"max_gap_s", max_gap_s},
          {"invalid_samples", invalid},
          {"gaps_skipped", gaps},
          {"gap_seconds", total_s},
          {"longest_interval_s", longest_s}};
}

// Index of the keyframe within `tolerance` of t_ns, or -1.
long find_keyframe(const Trajectory& keyframes, TimeNs t_ns, TimeNs tolerance) {
  auto it = std::lower_bound(keyframes.begin(), keyframes.end(), t_ns,
                             [](const StampedPose& p, TimeNs t) { return p.t_ns < t; });
  long best = -1;
  TimeNs best_dt = tolerance + 1;
  for (auto c : {it, it == keyframes.begin() ? it : it - 1}) {
    if (c == keyframes.end()) continue;
    const TimeNs dt = std::abs(c->t_ns - t_ns);
    if (dt < best_dt) {
      best_dt = dt;
      best = static_cast<long>(c - keyframes.begin());
    }
  }
  return best;
}

struct Inputs {
  slam::RefineInput solver;
  Trajectory map_poses;  // the keyframes as recorded (before any are dropped)
  json report = json::object();
  json warnings = json::array();
  std::string dvl_sensor;
  Pose3 T_body_dvl_manifest = Pose3::Identity();
};

// A DVL riding a servo tray (seed 001's HAUV) measures in a frame that turns with the tray:
// its samples go into the frame of its manifest extrinsic (angle 0), which the solver holds
// fixed. Without this the solver read tray-turned velocities as body motion (keel-sim
// hauv-hull, whole survey: ATE 0.54 m with the DVL against 0.02 m without).
json undo_tray_rotation(const io::MissionReader& reader, const proto::SensorSpec& dvl,
                        const Pose3& T_body_dvl0, const RefineStageOptions& options, Inputs& in) {
  const proto::SensorSpec* servo = reader.manifest().find_sensor(dvl.mounted_on);
  if (!servo || servo->type != SensorType::kServo)
    throw std::runtime_error("sensor '" + dvl.name + "': mounted_on '" + dvl.mounted_on +
                             "' is not a servo sensor of the mission");
  const std::optional<Pose3> T_body_servo = reader.extrinsic(servo->name);
  if (!T_body_servo)
    throw std::runtime_error("sensor '" + servo->name +
                             "': no T_body_sensor; the DVL on its tray needs the tray's pivot");
  try {
    const TrayDvlStats stats =
        rotate_tray_dvl(in.solver.dvl, reader.read_servo(servo->name), *T_body_servo,
                        tray_axis(*servo), T_body_dvl0, TimeNs(0.5e9 * options.servo_window_s));
    return {{"servo", servo->name},
            {"samples_turned", stats.rotated},
            {"samples_without_angle", stats.without_angle},
            {"max_angle_deg", stats.max_angle_rad * 180.0 / M_PI}};
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("sensor '" + dvl.name + "' on '" + servo->name + "': " + e.what());
  }
}

// Keeps the keyframes for which keep[k] is true.
Trajectory select(const Trajectory& keyframes, const std::vector<bool>& keep) {
  Trajectory out;
  for (size_t k = 0; k < keyframes.size(); ++k)
    if (keep[k]) out.push_back(keyframes[k]);
  return out;
}

void require_keyframes(const Trajectory& keyframes, const std::string& why) {
  if (keyframes.size() < 2)
    throw std::runtime_error("refine needs at least 2 keyframes " + why + ", found " +
                             std::to_string(keyframes.size()));
}

// Per-axis RMS of the odometry increments' disagreement with the MAP increments, [t, phi] in
// the frame of keyframe i, over the edges that carry information; added to every such edge's
// covariance: Sigma' = Sigma + D, D = diag(rms^2). Written as
// information' = D^-1/2 M (I + M)^-1 D^-1/2 with M = D^1/2 information D^1/2, which needs no
// inverse of the (possibly singular) information and keeps its correlations (GICP's
// point-to-plane information couples translation with roll and pitch through the lidar's lever
// arm); 1 / its diagonal is the conditional variance, smaller than the marginal one. For the
// diagonal information of recorded odometry this is the old per-axis sum of variances.
void widen_by_map_disagreement(Inputs& in) {
  const auto& edges = in.solver.odometry;
  const Trajectory& keyframes = in.solver.keyframes;
  if (edges.size() != keyframes.size() - 1) return;
  Eigen::Matrix<double, 6, 1> sum = Eigen::Matrix<double, 6, 1>::Zero();
  size_t used = 0;
  for (size_t k = 0; k < edges.size(); ++k) {
    if (edges[k].information.isZero()) continue;  // no measurement (a failed registration)
    const Pose3 T_map = keyframes[k].T_world_body.inverse() * keyframes[k + 1].T_world_body;
    const Pose3& T_odo = edges[k].T_i_j;
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = T_odo.translation() - T_map.translation();
    e.tail<3>() = slam::so3_log(T_map.linear().transpose() * T_odo.linear());
    sum += e.cwiseProduct(e);
    ++used;
  }
  if (used == 0) return;
  const Eigen::Matrix<double, 6, 1> rms = (sum / static_cast<double>(used)).cwiseSqrt();
  // A floor keeps D invertible when an axis agrees exactly (1 um, 1 urad).
  const Eigen::Matrix<double, 6, 1> d_sqrt = rms.cwiseMax(1e-6);
  const slam::Matrix6d D_half = d_sqrt.asDiagonal();
  const slam::Matrix6d D_inv_half = d_sqrt.cwiseInverse().asDiagonal();
  for (auto& edge : in.solver.odometry) {
    const slam::Matrix6d M = D_half * edge.information * D_half;
    // M and (I + M) commute, so M (I + M)^-1 = (I + M)^-1 M.
    const slam::Matrix6d widened =
        D_inv_half * (slam::Matrix6d::Identity() + M).ldlt().solve(M) * D_inv_half;
    edge.information = 0.5 * (widened + widened.transpose());
  }
  in.report["odometry"]["disagreement_with_map_rms"] = {
      {"translation_m", {rms[0], rms[1], rms[2]}},
      {"rotation_deg", {rms[3] * kRadToDeg, rms[4] * kRadToDeg, rms[5] * kRadToDeg}}};
}

// Step 3a: the recorded odometry at the keyframe stamps; keyframes outside it are dropped.
void recorded_odometry(const io::MissionReader& reader, const RefineStageOptions& options,
                       Inputs& in) {
  const Trajectory odometry = reader.read_trajectory("odometry");
  if (odometry.size() < 2)
    throw std::runtime_error("trajectories.odometry: expected at least 2 poses, found " +
                             std::to_string(odometry.size()));
  std::vector<bool> keep(in.solver.keyframes.size());
  for (size_t k = 0; k < keep.size(); ++k)
    keep[k] = in.solver.keyframes[k].t_ns >= odometry.front().t_ns &&
              in.solver.keyframes[k].t_ns <= odometry.back().t_ns;
  const size_t before = in.solver.keyframes.size();
  in.solver.keyframes = select(in.solver.keyframes, keep);
  require_keyframes(in.solver.keyframes, "inside the span of trajectories.odometry");
  slam::OdometryNoise noise;
  noise.sigma_translation_m = options.odometry_sigma_translation_m;
  noise.sigma_translation_per_m = options.odometry_sigma_translation_per_m;
  noise.sigma_rotation_rad = options.odometry_sigma_rotation_rad;
  noise.sigma_rotation_per_rad = options.odometry_sigma_rotation_per_rad;
  std::vector<TimeNs> stamps;
  for (const auto& p : in.solver.keyframes) stamps.push_back(p.t_ns);
  in.solver.odometry = slam::relative_poses_from_trajectory(odometry, stamps, noise);
  in.report["odometry"] = span_json(odometry.front().t_ns, odometry.back().t_ns);
  if (options.odometry_noise_from_map) widen_by_map_disagreement(in);
  in.report["odometry"]["source"] = "recorded";
  in.report["odometry"]["poses"] = odometry.size();
  in.report["odometry"]["edges"] = in.solver.odometry.size();
  in.report["keyframes"]["dropped_outside_odometry"] = before - in.solver.keyframes.size();
}

// Step 3b: GICP between the keyframe scans of the lidar (the scan nearest each keyframe,
// within the solver's time tolerance); keyframes without a scan are dropped.
void gicp_odometry(const io::MissionReader& reader, const RefineStageOptions& options,
                   const slam::RefineOptions& solver_options, StageContext& context, Inputs& in) {
  const proto::SensorSpec* lidar =
      pick_sensor(reader.manifest(), options.lidar_sensor, SensorType::kLidar, "lidar_sensor");
  if (!lidar)
    throw std::runtime_error(
        "refine needs odometry: the mission has neither trajectories.odometry nor a lidar "
        "sensor for GICP scan matching");
  const std::optional<Pose3> T_body_lidar = reader.extrinsic(lidar->name);
  if (!T_body_lidar)
    throw std::runtime_error("sensor '" + lidar->name +
                             "': no T_body_sensor (neither in mission.yaml nor /tf_static); "
                             "GICP odometry needs it");
  const Trajectory& keyframes = in.solver.keyframes;
  const TimeNs tolerance = seconds_to_ns(solver_options.measurement_time_tolerance_s);
  std::vector<PointCloud> scans(keyframes.size());
  std::vector<TimeNs> best_dt(keyframes.size(), std::numeric_limits<TimeNs>::max());
  auto source = reader.open_scans(lidar->name);
  const size_t total = source->size();
  size_t read = 0;
  PointCloud cloud;
  while (true) {
    context.check_canceled();
    if (!source->next(cloud)) break;
    ++read;
    const long k = find_keyframe(keyframes, cloud.t_ns, tolerance);
    if (k >= 0 && std::abs(cloud.t_ns - keyframes[k].t_ns) < best_dt[k]) {
      best_dt[k] = std::abs(cloud.t_ns - keyframes[k].t_ns);
      scans[k] = cloud;
      scans[k].t_ns = keyframes[k].t_ns;
    }
    if (total > 0) context.progress(0.15 + 0.15 * static_cast<double>(read) / total);
  }
  std::vector<bool> keep(keyframes.size());
  std::vector<PointCloud> kept_scans;
  std::vector<Pose3> initial;
  for (size_t k = 0; k < keyframes.size(); ++k) {
    keep[k] = best_dt[k] != std::numeric_limits<TimeNs>::max();
    if (!keep[k]) continue;
    kept_scans.push_back(std::move(scans[k]));
    initial.push_back(keyframes[k].T_world_body);
  }
  const size_t before = keyframes.size();
  in.solver.keyframes = select(keyframes, keep);
  require_keyframes(in.solver.keyframes, "with a scan of '" + lidar->name + "'");
  context.check_canceled();
  in.solver.odometry = slam::relative_poses_from_scans(kept_scans, *T_body_lidar, initial);
  in.report["odometry"] = {{"source", "gicp"},
                           {"sensor", lidar->name},
                           {"scans_read", read},
                           {"edges", in.solver.odometry.size()}};
  // The point-to-plane information treats neighbouring residuals as independent and is far
  // too confident (millimetres); the disagreement with the MAP increments is the honest figure.
  if (options.odometry_noise_from_map) widen_by_map_disagreement(in);
  // A registration that did not converge or failed the outlier gate carries no information.
  // It is left out rather than passed on as a zero-information edge: that would flag its
  // keyframe degenerate, and the paper's zeroed biases there (Sec. IV-B), chained to the rest
  // by the bias random walks, pin b^a to zero over the whole mission (without DVL a 5 mm/s^2
  // turn-on bias then sagged a 30 s mission by 0.5 m).
  const size_t matched = in.solver.odometry.size();
  auto& edges = in.solver.odometry;
  edges.erase(
      std::remove_if(edges.begin(), edges.end(),
                     [](const slam::RelativePoseMeasurement& m) { return m.information.isZero(); }),
      edges.end());
  in.report["odometry"]["edges"] = edges.size();
  in.report["odometry"]["edges_rejected"] = matched - edges.size();
  in.report["keyframes"]["dropped_without_scan"] = before - in.solver.keyframes.size();
}

// Step 4a: loop closures whose stamps both match a keyframe; the others are counted.
void loop_closures(const io::MissionReader& reader, const slam::RefineOptions& solver_options,
                   Inputs& in) {
  const auto loops = reader.read_loop_closures();
  const TimeNs tolerance = seconds_to_ns(solver_options.measurement_time_tolerance_s);
  size_t skipped = 0;
  for (const auto& loop : loops) {
    if (find_keyframe(in.solver.keyframes, loop.t_i_ns, tolerance) < 0 ||
        find_keyframe(in.solver.keyframes, loop.t_j_ns, tolerance) < 0) {
      ++skipped;
      continue;
    }
    slam::RelativePoseMeasurement m;
    m.t_i_ns = loop.t_i_ns;
    m.t_j_ns = loop.t_j_ns;
    m.T_i_j = loop.T_body_i_body_j;
    m.information.setZero();
    m.information.topLeftCorner<3, 3>().diagonal().setConstant(1.0 /
                                                               (loop.sigma_t_m * loop.sigma_t_m));
    m.information.bottomRightCorner<3, 3>().diagonal().setConstant(
        1.0 / (loop.sigma_r_rad * loop.sigma_r_rad));
    in.solver.loop_closures.push_back(m);
  }
  in.report["loop_closures"] = {{"count", loops.size()},
                                {"used", in.solver.loop_closures.size()},
                                {"skipped_no_keyframe", skipped}};
  if (skipped > 0)
    in.warnings.push_back(std::to_string(skipped) +
                          " loop closures match no keyframe stamp and were left out");
}

// Step 4b: IMU and DVL samples with their extrinsics and noise figures.
void inertial_inputs(const io::MissionReader& reader, const RefineStageOptions& options,
                     slam::RefineOptions& solver_options, Inputs& in) {
  const auto& manifest = reader.manifest();
  const proto::SensorSpec* imu =
      pick_sensor(manifest, options.imu_sensor, SensorType::kImu, "imu_sensor");
  if (!imu)
    throw std::runtime_error(
        "refine needs an IMU: the mission has no sensor of type imu (mission.yaml sensors)");
  in.solver.imu = to_slam(reader.read_imu(imu->name));
  if (in.solver.imu.size() < 2)
    throw std::runtime_error("sensor '" + imu->name + "': expected IMU samples, found " +
                             std::to_string(in.solver.imu.size()));
  const std::optional<Pose3> T_body_imu = reader.extrinsic(imu->name);
  in.solver.T_body_imu = T_body_imu.value_or(Pose3::Identity());
  if (!T_body_imu)
    in.warnings.push_back("sensor '" + imu->name +
                          "' has no T_body_sensor; the IMU frame is taken as the body frame");
  solver_options.imu_noise = {imu->noise.imu.gyro_noise_density, imu->noise.imu.accel_noise_density,
                              imu->noise.imu.gyro_random_walk, imu->noise.imu.accel_random_walk};
  in.report["imu"] = span_json(in.solver.imu.front().t_ns, in.solver.imu.back().t_ns);
  in.report["imu"]["sensor"] = imu->name;
  in.report["imu"]["samples"] = in.solver.imu.size();
  in.report["imu"]["extrinsic"] = T_body_imu ? "given" : "identity (none given)";

  in.report["dvl"] = nullptr;
  if (!options.dvl) return;
  const proto::SensorSpec* dvl =
      pick_sensor(manifest, options.dvl_sensor, SensorType::kDvl, "dvl_sensor");
  if (!dvl)
    throw std::runtime_error(
        "refine fuses a DVL, but the mission has no sensor of type dvl (mission.yaml sensors); "
        "set refine.dvl=false to refine without one");
  const std::optional<Pose3> T_body_dvl = reader.extrinsic(dvl->name);
  if (!T_body_dvl)
    throw std::runtime_error("sensor '" + dvl->name +
                             "': no T_body_sensor (neither in mission.yaml nor /tf_static); "
                             "DVL fusion needs the lever arm and rotation");
  in.solver.dvl = to_slam(reader.read_dvl(dvl->name));
  in.solver.T_body_dvl = *T_body_dvl;
  in.T_body_dvl_manifest = *T_body_dvl;
  in.dvl_sensor = dvl->name;
  solver_options.dvl_noise.velocity_sigma_rel = dvl->noise.dvl.velocity_sigma_rel;
  solver_options.dvl_noise.bias_random_walk_rel = dvl->noise.dvl.bias_random_walk_rel;
  if (in.solver.dvl.empty()) throw std::runtime_error("sensor '" + dvl->name + "': no samples");
  in.report["dvl"] = span_json(in.solver.dvl.front().t_ns, in.solver.dvl.back().t_ns);
  in.report["dvl"]["sensor"] = dvl->name;
  in.report["dvl"]["samples"] = in.solver.dvl.size();
  if (!dvl->mounted_on.empty())
    in.report["dvl"]["servo_tray"] = undo_tray_rotation(reader, *dvl, *T_body_dvl, options, in);
}

Inputs gather_inputs(const io::MissionReader& reader, const RefineStageOptions& options,
                     slam::RefineOptions& solver_options, StageContext& context) {
  Inputs in;
  // Step 2: keyframes.
  if (!reader.has_trajectory("map"))
    throw std::runtime_error(
        "refine needs the recorded keyframe poses: mission.yaml has no trajectories.map");
  in.map_poses = reader.read_trajectory("map");
  in.solver.keyframes = in.map_poses;
  require_keyframes(in.map_poses, "in trajectories.map");
  in.report["keyframes"] = span_json(in.map_poses.front().t_ns, in.map_poses.back().t_ns);
  in.report["keyframes"]["source"] = "map";
  in.report["keyframes"]["recorded"] = in.map_poses.size();
  context.progress(0.05);
  context.check_canceled();

  // Step 4b first: a mission without the sensors fails before any scan matching.
  inertial_inputs(reader, options, solver_options, in);
  context.progress(0.15);
  context.check_canceled();

  // Step 3: odometry edges.
  const bool recorded = reader.has_trajectory("odometry");
  if (options.odometry == "recorded" && !recorded)
    throw std::runtime_error(
        "options.refine.odometry=recorded, but mission.yaml has no trajectories.odometry");
  if (options.odometry == "gicp" || (options.odometry == "auto" && !recorded))
    gicp_odometry(reader, options, solver_options, context, in);
  else
    recorded_odometry(reader, options, in);
  context.progress(0.3);
  context.check_canceled();

  // Step 4a: loop closures.
  if (options.loop_closures)
    loop_closures(reader, solver_options, in);
  else
    in.report["loop_closures"] = {{"used", 0}, {"disabled", true}};
  in.report["keyframes"]["used"] = in.solver.keyframes.size();
  return in;
}

// ---- report -------------------------------------------------------------------------------

json solver_json(const slam::RefineSummary& s) {
  return {{"iterations", s.iterations},
          {"solve_time_s", s.solve_time_s},
          {"covariance_time_s", s.covariance_time_s},
          {"total_time_s", s.total_time_s},
          {"initial_cost", s.initial_cost},
          {"final_cost", s.final_cost},
          {"converged", s.converged},
          {"keyframes", s.num_keyframes},
          {"factors",
           {{"odometry", s.num_odometry_factors},
            {"imu", s.num_imu_factors},
            {"dvl", s.num_dvl_factors},
            {"loop_closures", s.num_loop_closures},
            {"map_anchors", s.num_map_anchors}}},
          {"intervals_skipped",
           {{"imu_gaps", s.num_imu_intervals_skipped}, {"dvl_gaps", s.num_dvl_intervals_skipped}}},
          {"pseudo_samples", s.num_pseudo_samples},
          {"covariance_ok", s.covariance_ok},
          {"ceres", s.ceres_report}};
}

// Runs of consecutive degenerate keyframes, as stamp ranges.
json degenerate_json(const slam::RefineResult& r) {
  json ranges = json::array();
  size_t count = 0;
  for (size_t k = 0; k < r.keyframes.size(); ++k) {
    if (!r.keyframes[k].degenerate) continue;
    ++count;
    const bool continues = k > 0 && r.keyframes[k - 1].degenerate;
    if (continues) {
      ranges.back()["t_last_s"] = ns_to_seconds(r.keyframes[k].t_ns);
      ranges.back()["keyframes"] = ranges.back()["keyframes"].get<size_t>() + 1;
    } else {
      ranges.push_back({{"t_first_s", ns_to_seconds(r.keyframes[k].t_ns)},
                        {"t_last_s", ns_to_seconds(r.keyframes[k].t_ns)},
                        {"keyframes", 1}});
    }
  }
  return {{"count", count}, {"ranges", ranges}};
}

// What truth.yaml says about the DVL (keel-sim missions): s_d and T_body_dvl.
struct DvlTruth {
  std::optional<double> scale;
  std::optional<Eigen::Matrix3d> R_body_dvl;
};

DvlTruth read_dvl_truth(const io::Mission& mission, const std::string& dvl_sensor, json& warnings) {
  DvlTruth truth;
  if (mission.ground_truth_path.empty()) return truth;
  const json doc = io::load_yaml_file(mission.ground_truth_path);
  if (doc.contains("dvl_scale") && doc["dvl_scale"].is_number())
    truth.scale = doc["dvl_scale"].get<double>();
  if (!dvl_sensor.empty() && doc.contains("extrinsics") && doc["extrinsics"].is_object() &&
      doc["extrinsics"].contains(dvl_sensor)) {
    const auto e = proto::Extrinsic::from_json(doc["extrinsics"][dvl_sensor],
                                               "truth.yaml: extrinsics." + dvl_sensor);
    const auto& q = e.rotation_xyzw;
    truth.R_body_dvl = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
  }
  if (!truth.scale && !truth.R_body_dvl)
    warnings.push_back(io::display_path(mission.ground_truth_path) +
                       ": no dvl_scale and no DVL extrinsic to compare with");
  return truth;
}

json vector_deg(const Eigen::Vector3d& v_rad) {
  return {v_rad.x() * kRadToDeg, v_rad.y() * kRadToDeg, v_rad.z() * kRadToDeg};
}

json calibration_json(const slam::RefineResult& r, const RefineStageOptions& options,
                      const Inputs& in, const DvlTruth& truth) {
  json scale = {{"estimated", options.estimate_dvl_scale},
                {"value", r.dvl_scale},
                {"sigma", r.dvl_scale_sigma},
                {"true", truth.scale ? json(*truth.scale) : json(nullptr)}};
  const Eigen::Matrix3d R_est = r.q_body_dvl.toRotationMatrix();
  const Eigen::Matrix3d& R_init = in.T_body_dvl_manifest.linear();
  const Eigen::Vector3d sigma = r.dvl_rotation_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  json rotation = {
      {"estimated", options.estimate_dvl_rotation},
      {"q_body_dvl_xyzw", {r.q_body_dvl.x(), r.q_body_dvl.y(), r.q_body_dvl.z(), r.q_body_dvl.w()}},
      // R_est = R_init Exp(correction): the change from mission.yaml, in DVL-frame axes.
      {"correction_deg", vector_deg(slam::so3_log(R_init.transpose() * R_est))},
      {"sigma_deg", vector_deg(sigma)},
      {"error_vs_truth_deg", nullptr}};
  if (truth.R_body_dvl)
    rotation["error_vs_truth_deg"] =
        vector_deg(slam::so3_log(truth.R_body_dvl->transpose() * R_est));
  return {{"dvl_scale", scale}, {"dvl_rotation", rotation}};
}

json metrics_json(const slam::ErrorStatistics& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"std", s.std},
          {"min", s.min},   {"max", s.max},   {"count", s.count}};
}

// ATE and RPE of one estimate against ground truth.
json evaluate(const Trajectory& truth, const Trajectory& estimate,
              const RefineStageOptions& options) {
  slam::AssociationOptions association;
  association.max_difference_s = options.ate_max_time_difference_s;
  const auto ate =
      slam::absolute_trajectory_error(truth, estimate, slam::Alignment::kSE3, association);
  slam::RpeOptions rpe_options;
  rpe_options.delta = options.rpe_delta_m;
  rpe_options.unit = slam::DeltaUnit::kMeters;
  rpe_options.pairs_from_reference = true;  // the same pairs for every estimate
  json out = {{"ate",
               {{"translation_m", metrics_json(ate.translation_m)},
                {"rotation_deg", metrics_json(ate.rotation_deg)}}}};
  try {
    const auto rpe = slam::relative_pose_error(truth, estimate, rpe_options, association);
    out["rpe"] = {{"translation_m", metrics_json(rpe.translation_m)},
                  {"rotation_deg", metrics_json(rpe.rotation_deg)}};
  } catch (const std::invalid_argument& e) {
    out["rpe"] = {{"error", e.what()}};  // e.g. a path shorter than delta
  }
  return out;
}

// Table II of seed 000: MAP poses, refined without DVL, refined with DVL.
json evaluation_json(const Trajectory& truth, const Trajectory& map_poses,
                     const Trajectory* without_dvl, const Trajectory* with_dvl,
                     const RefineStageOptions& options, const std::string& truth_source) {
  json rows = json::object();
  rows["map"] = evaluate(truth, map_poses, options);
  rows["refined_without_dvl"] =
      without_dvl ? evaluate(truth, *without_dvl, options) : json(nullptr);
  rows["refined_with_dvl"] = with_dvl ? evaluate(truth, *with_dvl, options) : json(nullptr);
  json out = {{"ground_truth", truth_source},
              {"ate_method",
               "SE(3) Umeyama alignment (Zhang & Scaramuzza 2018, as evo -a); poses associated "
               "by nearest stamp within " +
                   std::to_string(options.ate_max_time_difference_s) + " s"},
              {"rpe_method", "consecutive pose pairs " + std::to_string(options.rpe_delta_m) +
                                 " m apart along the ground-truth path (delta unit: metres)"},
              {"table", rows}};
  auto ate_rmse = [&](const char* row) -> std::optional<double> {
    if (rows[row].is_null()) return std::nullopt;
    return rows[row]["ate"]["translation_m"]["rmse"].get<double>();
  };
  const auto map = ate_rmse("map"), with = ate_rmse("refined_with_dvl"),
             without = ate_rmse("refined_without_dvl");
  if (map && with && *map > 0.0)
    out["ate_reduction_with_dvl_vs_map_percent"] = 100.0 * (1.0 - *with / *map);
  if (map && without && *map > 0.0)
    out["ate_reduction_without_dvl_vs_map_percent"] = 100.0 * (1.0 - *without / *map);
  return out;
}

// trajectories.json: the recorded MAP poses of the keyframes used (Table II's MAP row), the
// written refinement, the one without DVL when both were solved, and the ground truth; each
// estimate with its per-pose ATE under the report's alignment when there is ground truth.
void write_trajectories(const std::filesystem::path& work_dir, const Trajectory& recorded,
                        const Trajectory& refined, const Trajectory* refined_no_dvl,
                        const Trajectory& truth, const RefineStageOptions& options) {
  slam::AssociationOptions association;
  association.max_difference_s = options.ate_max_time_difference_s;
  auto entry = [&](const std::string& name, const Trajectory& poses) {
    TrajectoryEntry e{name, "world", poses, {}};
    if (!truth.empty()) e.ate_m = per_pose_ate(truth, poses, association);
    return e;
  };
  std::vector<TrajectoryEntry> entries = {entry("recorded", recorded), entry("refined", refined)};
  if (refined_no_dvl) entries.push_back(entry("refined_no_dvl", *refined_no_dvl));
  if (!truth.empty()) entries.push_back({"ground_truth", "world", truth, {}});
  add_to_trajectories_file(work_dir, entries);
}

std::string ground_truth_source(const io::Mission& mission) {
  const auto& spec = mission.manifest.trajectories.at("ground_truth");
  return spec.topic.empty() ? spec.file : "topic " + spec.topic;
}

// Standard deviations along the world (translation) or body (rotation) axes, and along the
// covariance's principal axes (largest first), in `unit_scale` units.
json covariance_json(const Eigen::Matrix3d& covariance, double unit_scale) {
  const Eigen::Vector3d axes = covariance.diagonal().cwiseMax(0.0).cwiseSqrt() * unit_scale;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(covariance);
  const Eigen::Vector3d principal = es.eigenvalues().cwiseMax(0.0).cwiseSqrt() * unit_scale;
  const Eigen::Vector3d largest = es.eigenvectors().col(2);
  return {{"axes", {axes.x(), axes.y(), axes.z()}},
          {"principal", {principal.z(), principal.y(), principal.x()}},
          {"largest_direction", {largest.x(), largest.y(), largest.z()}}};
}

json map_noise_json(const slam::RefineResult& r, bool anchors) {
  return {{"anchors", anchors},
          {"estimated", r.map_noise_estimated},
          {"sigma_translation_m", covariance_json(r.map_noise.translation_covariance, 1.0)},
          {"drift_m_per_sqrt_m", covariance_json(r.map_noise.drift_covariance_per_m, 1.0)},
          {"sigma_rotation_deg", covariance_json(r.map_noise.rotation_covariance, kRadToDeg)}};
}

// Runs of consecutive flagged keyframes, as stamp ranges.
json flagged_ranges(const slam::MapAgreement& a) {
  json ranges = json::array();
  for (size_t k = 0; k < a.keyframes.size(); ++k) {
    if (!a.keyframes[k].flagged) continue;
    const double t = ns_to_seconds(a.keyframes[k].t_ns);
    if (k > 0 && a.keyframes[k - 1].flagged) {
      ranges.back()["t_last_s"] = t;
      ranges.back()["keyframes"] = ranges.back()["keyframes"].get<int>() + 1;
    } else {
      ranges.push_back({{"t_first_s", t}, {"t_last_s", t}, {"keyframes", 1}});
    }
  }
  return ranges;
}

json self_check_json(const slam::MapAgreement& a) {
  return {{"keyframes", a.keyframes.size()},
          {"flagged_keyframes", a.flagged},
          {"flagged_ranges", flagged_ranges(a)},
          {"chi2_threshold", a.chi2_threshold},
          {"translation_m", {{"rms", a.translation_rms_m}, {"max", a.translation_max_m}}},
          {"rotation_deg",
           {{"rms", a.rotation_rms_rad * kRadToDeg}, {"max", a.rotation_max_rad * kRadToDeg}}},
          {"per_keyframe", kSelfCheckFile}};
}

void write_self_check_csv(const std::filesystem::path& path, const slam::MapAgreement& a) {
  std::ofstream out(path);
  out << "t_s,dx_m,dy_m,dz_m,moved_m,droll_deg,dpitch_deg,dyaw_deg,turned_deg,drift_path_m,"
         "mahalanobis_translation,mahalanobis_rotation,flagged\n";
  char line[512];
  for (const auto& m : a.keyframes) {
    const Eigen::Vector3d r = m.rotation_rad * kRadToDeg;
    std::snprintf(
        line, sizeof line, "%.9f,%.6f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f,%.5f,%.3f,%.4f,%.4f,%d\n",
        ns_to_seconds(m.t_ns), m.translation_m.x(), m.translation_m.y(), m.translation_m.z(),
        m.translation_m.norm(), r.x(), r.y(), r.z(), r.norm(), m.drift_path_m,
        m.mahalanobis_translation, m.mahalanobis_rotation, m.flagged ? 1 : 0);
    out << line;
  }
  if (!out) throw std::runtime_error(path.string() + ": could not write the self-check");
}

// ---- the stage ----------------------------------------------------------------------------

class RefineStage : public Stage {
 public:
  std::string name() const override { return "refine"; }
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override {
    return report_html::refine_section(section, inputs.trajectories);
  }

  StageResult run(StageContext& context) override {
    // Step 1: options and the mission.
    const RefineStageOptions options = RefineStageOptions::from_json(context.options);
    slam::RefineOptions solver_options = options.solver_options();
    io::MissionReader reader(io::load_mission(context.mission_dir));
    context.check_canceled();

    // Steps 2-4: keyframes, odometry, loop closures, IMU and DVL.
    Inputs in = gather_inputs(reader, options, solver_options, context);
    const bool has_truth = reader.has_trajectory("ground_truth");
    context.log("refine: " + std::to_string(in.solver.keyframes.size()) + " keyframes, " +
                std::to_string(in.solver.odometry.size()) + " odometry edges, " +
                std::to_string(in.solver.loop_closures.size()) + " loop closures, " +
                std::to_string(in.solver.imu.size()) + " IMU and " +
                std::to_string(in.solver.dvl.size()) + " DVL samples");

    // Step 5: the solves. The solver has no iteration callback, so cancellation is checked
    // between them.
    const bool second_solve = options.dvl && has_truth && options.compare_without_dvl;
    std::optional<slam::RefineResult> with_dvl, without_dvl;
    if (options.dvl) {
      solver_options.use_dvl = true;
      with_dvl = slam::refine_trajectory(in.solver, solver_options);
      log_solve(context, "with DVL", *with_dvl);
      context.progress(second_solve ? 0.6 : 0.9);
      context.check_canceled();
    }
    if (!options.dvl || second_solve) {
      slam::RefineOptions no_dvl = solver_options;
      no_dvl.use_dvl = false;
      slam::RefineInput input = in.solver;
      input.dvl.clear();
      without_dvl = slam::refine_trajectory(input, no_dvl);
      log_solve(context, "without DVL", *without_dvl);
      context.progress(0.9);
      context.check_canceled();
    }
    const slam::RefineResult& result = with_dvl ? *with_dvl : *without_dvl;

    // Step 6: the artifact and the report.
    const Trajectory refined = result.trajectory();
    io::write_tum(context.work_dir / kRefinedTrajectoryFile, refined);
    StageResult out;
    out.artifacts.push_back(kRefinedTrajectoryFile);
    // The self-check against the MAP poses the solve started from, with the MAP noise it used
    // (the options' fixed noise when it was not estimated).
    std::vector<double> drift_path;
    for (const auto& k : result.keyframes) drift_path.push_back(k.map_drift_path_m);
    const slam::MapAgreement agreement =
        slam::compare_with_map(in.solver.keyframes, refined, result.map_noise, drift_path);
    write_self_check_csv(context.work_dir / kSelfCheckFile, agreement);
    out.artifacts.push_back(kSelfCheckFile);
    json& r = out.report;
    r["inputs"] = in.report;
    r["options"] = options_json(options);
    r["solves"] = second_solve
                      ? "two: with DVL fusion (written to trajectory_refined.tum) and without, "
                        "because ground truth is present (Table II of seed 000)"
                      : (options.dvl ? "one, with DVL fusion" : "one, without DVL fusion");
    r["solver"] = solver_json(result.summary);
    if (with_dvl && without_dvl) r["solver_without_dvl"] = solver_json(without_dvl->summary);
    r["degenerate_keyframes"] = degenerate_json(result);
    r["map_noise"] = map_noise_json(result, options.map_anchors);
    r["self_check"] = self_check_json(agreement);
    r["dvl"] = nullptr;
    if (with_dvl) {
      const DvlTruth truth = read_dvl_truth(reader.mission(), in.dvl_sensor, in.warnings);
      r["dvl"] = calibration_json(*with_dvl, options, in, truth);
      r["dvl"]["gaps"] = dvl_gaps(in.solver.dvl, options.max_dvl_gap_s);
      r["dvl"]["gaps"]["intervals_without_dvl_factor"] =
          with_dvl->summary.num_dvl_intervals_skipped;
    }
    r["evaluation"] = nullptr;
    const Trajectory refined_without = without_dvl ? without_dvl->trajectory() : Trajectory{};
    const Trajectory truth = has_truth ? reader.read_trajectory("ground_truth") : Trajectory{};
    if (has_truth) {
      context.check_canceled();
      const Trajectory& map_used = in.solver.keyframes;  // the recorded poses of the keyframes
      r["evaluation"] = evaluation_json(truth, map_used, without_dvl ? &refined_without : nullptr,
                                        with_dvl ? &refined : nullptr, options,
                                        ground_truth_source(reader.mission()));
    }
    write_trajectories(context.work_dir, in.solver.keyframes, refined,
                       with_dvl && without_dvl ? &refined_without : nullptr, truth, options);
    out.artifacts.push_back(kTrajectoriesFile);
    r["warnings"] = in.warnings;
    context.progress(1.0);
    return out;
  }

 private:
  static void log_solve(StageContext& context, const std::string& what,
                        const slam::RefineResult& r) {
    context.log("refine: solved " + what + " in " + std::to_string(r.summary.total_time_s) +
                " s, " + std::to_string(r.summary.iterations) + " iterations, cost " +
                std::to_string(r.summary.initial_cost) + " -> " +
                std::to_string(r.summary.final_cost));
  }

  static json options_json(const RefineStageOptions& o) {
    return {{"dvl", o.dvl},
            {"estimate_dvl_scale", o.estimate_dvl_scale},
            {"estimate_dvl_rotation", o.estimate_dvl_rotation},
            {"odometry", o.odometry},
            {"loop_closures", o.loop_closures},
            {"odometry_noise_from_map", o.odometry_noise_from_map},
            {"degeneracy", o.degeneracy},
            {"degeneracy_sigma_translation_m", o.degeneracy_sigma_translation_m},
            {"degeneracy_sigma_rotation_rad", o.degeneracy_sigma_rotation_rad},
            {"imu_position_when_degenerate", o.imu_position_when_degenerate},
            {"map_anchors", o.map_anchors},
            {"map_sigma_translation_m", o.map_sigma_translation_m},
            {"map_sigma_rotation_rad", o.map_sigma_rotation_rad},
            {"map_drift_per_sqrt_m", o.map_drift_per_sqrt_m},
            {"estimate_map_noise", o.estimate_map_noise},
            {"max_dvl_gap_s", o.max_dvl_gap_s},
            {"servo_window_s", o.servo_window_s},
            {"rpe_delta_m", o.rpe_delta_m}};
  }
};

}  // namespace

RefineStageOptions RefineStageOptions::from_json(const json& options) {
  RefineStageOptions o;
  if (options.is_null()) return o;
  StageOptionReader r(options, "refine");
  o.imu_sensor = r.optional<std::string>("imu_sensor", o.imu_sensor);
  o.dvl_sensor = r.optional<std::string>("dvl_sensor", o.dvl_sensor);
  o.lidar_sensor = r.optional<std::string>("lidar_sensor", o.lidar_sensor);
  o.dvl = r.optional<bool>("dvl", o.dvl);
  o.estimate_dvl_scale = r.optional<bool>("estimate_dvl_scale", o.estimate_dvl_scale);
  o.dvl_scale_initial = r.optional<double>("dvl_scale_initial", o.dvl_scale_initial);
  o.dvl_scale_prior_sigma = r.optional<double>("dvl_scale_prior_sigma", o.dvl_scale_prior_sigma);
  o.estimate_dvl_rotation = r.optional<bool>("estimate_dvl_rotation", o.estimate_dvl_rotation);
  o.dvl_rotation_prior_sigma_deg =
      r.optional<double>("dvl_rotation_prior_sigma_deg", o.dvl_rotation_prior_sigma_deg);
  o.max_dvl_gap_s = r.optional<double>("max_dvl_gap_s", o.max_dvl_gap_s);
  o.servo_window_s = r.optional<double>("servo_window_s", o.servo_window_s);
  o.odometry = r.optional<std::string>("odometry", o.odometry);
  o.loop_closures = r.optional<bool>("loop_closures", o.loop_closures);
  o.odometry_sigma_translation_m =
      r.optional<double>("odometry_sigma_translation_m", o.odometry_sigma_translation_m);
  o.odometry_sigma_translation_per_m =
      r.optional<double>("odometry_sigma_translation_per_m", o.odometry_sigma_translation_per_m);
  o.odometry_sigma_rotation_rad =
      r.optional<double>("odometry_sigma_rotation_rad", o.odometry_sigma_rotation_rad);
  o.odometry_sigma_rotation_per_rad =
      r.optional<double>("odometry_sigma_rotation_per_rad", o.odometry_sigma_rotation_per_rad);
  o.odometry_noise_from_map =
      r.optional<bool>("odometry_noise_from_map", o.odometry_noise_from_map);
  o.degeneracy = r.optional<std::string>("degeneracy", o.degeneracy);
  o.degeneracy_sigma_translation_m =
      r.optional<double>("degeneracy_sigma_translation_m", o.degeneracy_sigma_translation_m);
  o.degeneracy_sigma_rotation_rad =
      r.optional<double>("degeneracy_sigma_rotation_rad", o.degeneracy_sigma_rotation_rad);
  o.imu_position_when_degenerate =
      r.optional<bool>("imu_position_when_degenerate", o.imu_position_when_degenerate);
  o.map_anchors = r.optional<bool>("map_anchors", o.map_anchors);
  o.map_sigma_translation_m =
      r.optional<double>("map_sigma_translation_m", o.map_sigma_translation_m);
  o.map_sigma_rotation_rad = r.optional<double>("map_sigma_rotation_rad", o.map_sigma_rotation_rad);
  o.map_drift_per_sqrt_m = r.optional<double>("map_drift_per_sqrt_m", o.map_drift_per_sqrt_m);
  o.estimate_map_noise = r.optional<bool>("estimate_map_noise", o.estimate_map_noise);
  o.max_iterations = r.optional<int>("max_iterations", o.max_iterations);
  o.relinearization_passes = r.optional<int>("relinearization_passes", o.relinearization_passes);
  o.threads = r.optional<int>("threads", o.threads);
  o.compare_without_dvl = r.optional<bool>("compare_without_dvl", o.compare_without_dvl);
  o.ate_max_time_difference_s =
      r.optional<double>("ate_max_time_difference_s", o.ate_max_time_difference_s);
  o.rpe_delta_m = r.optional<double>("rpe_delta_m", o.rpe_delta_m);
  r.finish();

  local_require(o.dvl_scale_initial > 0.5 && o.dvl_scale_initial < 1.5, "dvl_scale_initial",
          "a value in (0.5, 1.5)");
  local_require(o.dvl_scale_prior_sigma > 0.0, "dvl_scale_prior_sigma", "> 0");
  local_require(o.dvl_rotation_prior_sigma_deg > 0.0, "dvl_rotation_prior_sigma_deg", "> 0");
  local_require(o.max_dvl_gap_s > 0.0, "max_dvl_gap_s", "> 0");
  local_require(std::isfinite(o.servo_window_s) && o.servo_window_s >= 0.0, "servo_window_s", ">= 0");
  local_require(o.odometry == "auto" || o.odometry == "recorded" || o.odometry == "gicp", "odometry",
          "auto, recorded or gicp, got '" + o.odometry + "'");
  local_require(o.odometry_sigma_translation_m > 0.0, "odometry_sigma_translation_m", "> 0");
  local_require(o.odometry_sigma_translation_per_m >= 0.0, "odometry_sigma_translation_per_m", ">= 0");
  local_require(o.odometry_sigma_rotation_rad > 0.0, "odometry_sigma_rotation_rad", "> 0");
  local_require(o.odometry_sigma_rotation_per_rad >= 0.0, "odometry_sigma_rotation_per_rad", ">= 0");
  local_require(
      o.degeneracy == "drop" || o.degeneracy == "keep_well_conditioned" || o.degeneracy == "ignore",
      "degeneracy", "drop, keep_well_conditioned or ignore, got '" + o.degeneracy + "'");
  local_require(o.degeneracy_sigma_translation_m > 0.0, "degeneracy_sigma_translation_m", "> 0");
  local_require(o.degeneracy_sigma_rotation_rad > 0.0, "degeneracy_sigma_rotation_rad", "> 0");
  local_require(o.map_sigma_translation_m > 0.0, "map_sigma_translation_m", "> 0");
  local_require(o.map_sigma_rotation_rad > 0.0, "map_sigma_rotation_rad", "> 0");
  local_require(o.map_drift_per_sqrt_m > 0.0, "map_drift_per_sqrt_m", "> 0");
  local_require(o.max_iterations >= 1 && o.max_iterations <= 10000, "max_iterations",
          "an integer in [1, 10000]");
  local_require(o.relinearization_passes >= 1 && o.relinearization_passes <= 10, "relinearization_passes",
          "an integer in [1, 10]");
  local_require(o.threads >= 1 && o.threads <= 256, "threads", "an integer in [1, 256]");
  local_require(o.ate_max_time_difference_s >= 0.0, "ate_max_time_difference_s", ">= 0");
  local_require(o.rpe_delta_m > 0.0, "rpe_delta_m", "> 0");
  return o;
}

slam::RefineOptions RefineStageOptions::solver_options() const {
  slam::RefineOptions s;
  s.use_dvl = dvl;
  s.use_loop_closures = loop_closures;
  s.use_map_anchors = map_anchors;
  s.estimate_map_noise = estimate_map_noise;
  s.map_noise = slam::MapPoseNoise::isotropic(map_sigma_translation_m, map_sigma_rotation_rad,
                                              map_drift_per_sqrt_m);
  s.estimate_dvl_scale = estimate_dvl_scale;
  s.dvl_scale_initial = dvl_scale_initial;
  s.dvl_scale_prior_sigma = dvl_scale_prior_sigma;
  s.estimate_dvl_rotation = estimate_dvl_rotation;
  s.dvl_rotation_prior_sigma_rad = dvl_rotation_prior_sigma_deg * M_PI / 180.0;
  s.reconcile.max_dvl_gap_s = max_dvl_gap_s;
  s.imu_position_when_degenerate = imu_position_when_degenerate;
  s.degeneracy.min_eigenvalue_translation =
      1.0 / (degeneracy_sigma_translation_m * degeneracy_sigma_translation_m);
  s.degeneracy.min_eigenvalue_rotation =
      1.0 / (degeneracy_sigma_rotation_rad * degeneracy_sigma_rotation_rad);
  s.degeneracy_handling = degeneracy == "ignore" ? slam::DegeneracyHandling::kIgnore
                          : degeneracy == "keep_well_conditioned"
                              ? slam::DegeneracyHandling::kKeepWellConditioned
                              : slam::DegeneracyHandling::kDropFactor;
  s.max_iterations = max_iterations;
  s.relinearization_passes = relinearization_passes;
  s.num_threads = threads;
  return s;
}

std::unique_ptr<Stage> make_refine_stage() { return std::make_unique<RefineStage>(); }

}  // namespace keel::pipeline
