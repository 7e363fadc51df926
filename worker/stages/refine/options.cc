#include "worker/stages/refine/options.h"

#include <cmath>
#include <string>

#include "worker/pipeline/option_table.h"
#include "worker/stages/refine/stage.h"

namespace keel::pipeline {

namespace {

using O = RefineStageOptions;
using Noise = slam::OdometryNoise;

const char* const kSensors = "Sensors";
const char* const kDvl = "DVL fusion and calibration";
const char* const kOdometry = "Odometry, loop closures and MAP anchors";
const char* const kDegeneracy =
    "Degeneracy (seed 000 Sec. IV-B: \"fully relies on IMU and DVL factors when degeneracy is "
    "detected\")";
const char* const kSolver = "Solver";
const char* const kGnss = "GNSS (a `gnss` sensor in mission.yaml, issue 30)";
const char* const kEvaluation =
    "Evaluation (only when the mission has a `ground_truth` trajectory)";
const char* const kAsAbove = "as above";
const char* const kBeyond = "beyond the paper";

OptionDoc doc(const char* unit, const char* meaning, const char* source, const char* group,
              const char* default_text = "") {
  return {unit, meaning, source, group, default_text};
}

// A row for a member of the recorded odometry's noise (O::recorded_odometry_noise).
OptionRow<O> odometry_noise(const char* name, double Noise::*field, Check<double> check,
                            OptionDoc doc) {
  OptionRow<Noise> row = option(name, field, std::move(check), std::move(doc));
  return {row.name, row.type, row.doc,
          [read = row.read](O& o, const nlohmann::json& value, const std::string& path) {
            read(o.recorded_odometry_noise, value, path);
          },
          [write = row.write](const O& o) { return write(o.recorded_odometry_noise); }};
}

// In the order the stage asked for them before the table, which is the order of the "known"
// list of an unknown option's error; the docs list them by group.
const OptionTable<O>& table() {
  static const OptionTable<O> table(
      "refine",
      {
          option("imu_sensor", &O::imu_sensor,
                 doc("", "IMU whose samples make I_ij. Must name a sensor of that type.", "",
                     kSensors, "`\"\"` = first `imu` of mission.yaml")),
          option("dvl_sensor", &O::dvl_sensor,
                 doc("", "DVL whose velocities make D_ij (ignored when `dvl` = false)", "",
                     kSensors, "`\"\"` = first `dvl`")),
          option("lidar_sensor", &O::lidar_sensor,
                 doc("", "scans for GICP odometry (used only when the odometry is `gicp`)", "",
                     kSensors, "`\"\"` = first `lidar`")),
          option("dvl", &O::dvl,
                 doc("",
                     "fuse the DVL (D_ij factors and the b^v random walk). false: odometry, loops, "
                     "IMU only, and one solve",
                     "seed 000 Sec. IV", kDvl)),
          option("estimate_dvl_scale", &O::estimate_dvl_scale,
                 doc("",
                     "estimate the DVL scale factor s_d (Eq. (8)) as a state with a prior; false "
                     "holds it at `dvl_scale_initial`",
                     "beyond the paper: Sec. VII lists it as future work; Sec. V assumes s_d known",
                     kDvl)),
          option("dvl_scale_initial", &O::dvl_scale_initial, in_open_range(0.5, 1.5),
                 doc("", "in (0.5, 1.5): initial (and, if not estimated, fixed) s_d, dimensionless",
                     kAsAbove, kDvl)),
          option("dvl_scale_prior_sigma", &O::dvl_scale_prior_sigma, greater_than(0),
                 doc("", "> 0: σ of the prior on s_d around `dvl_scale_initial`, dimensionless",
                     kBeyond, kDvl)),
          option("estimate_dvl_rotation", &O::estimate_dvl_rotation,
                 doc("",
                     "estimate the DVL–IMU extrinsic rotation as a state, starting from "
                     "mission.yaml's T_body_sensor",
                     "beyond the paper: Sec. VII (online extrinsic calibration)", kDvl)),
          option("dvl_rotation_prior_sigma_deg", &O::dvl_rotation_prior_sigma_deg, greater_than(0),
                 doc("deg", "> 0: σ of the prior on that rotation, degrees per axis", kBeyond, kDvl,
                     "2.865 (= 0.05 rad)")),
          option("max_dvl_gap_s", &O::max_dvl_gap_s, greater_than(0),
                 doc("s",
                     "> 0: two consecutive valid DVL samples further apart than this (s) are not "
                     "bridged by Algorithm 1, so no D_ij spans the dropout; the report lists these "
                     "gaps. The solver also skips a D_ij whose pseudo samples lie further apart "
                     "than min(this, 0.1 s)",
                     "beyond the paper: Sec. VII (DVL drop-out); 0.5 s = 10 periods of a 20 Hz DVL",
                     kDvl)),
          option(
              "servo_window_s", &O::servo_window_s, Check<double>([](const double& v) {
                return std::isfinite(v) && v >= 0.0 ? std::string() : "expected a number >= 0";
              }),
              doc("s",
                  "≥ 0: a DVL riding a servo tray (`mounted_on`) measures in a frame that turns "
                  "with the tray: each velocity is turned back into the DVL's angle-0 frame (its "
                  "manifest extrinsic, which the solver holds) with the tray angle of a line "
                  "fitted to the servo samples within this window, s (0: interpolation; as "
                  "`ba.servo_window_s`). The DVL origin must lie on the tray's axis; samples "
                  "outside the servo stream become dropouts. The report's "
                  "`inputs.dvl.servo_tray` counts them",
                  "beyond the paper (seed 000 has no tray); without it keel-sim hauv-hull's "
                  "whole survey refined to ATE 0.54 m with the DVL against 0.02 m without, now "
                  "0.013 m",
                  kDvl)),
          option("odometry", &O::odometry, one_of({"auto", "recorded", "gicp"}),
                 doc("",
                     "`auto`, `recorded` or `gicp`: where the odometry edges L_ij come from: the "
                     "recorded `odometry` trajectory interpolated at the keyframes (`recorded`), "
                     "GICP between the keyframe scans of `lidar_sensor` (`gicp`), or the recorded "
                     "one when the mission has it, else GICP (`auto`). Keyframes outside the "
                     "odometry span, or without a scan within 0.05 s, are dropped",
                     "seed 000 Sec. III-A, Eq. (1) (L_ij, the lidar odometry); GICP is our "
                     "stand-in when none was recorded",
                     kOdometry)),
          option("loop_closures", &O::loop_closures,
                 doc("", "add loops.csv's loop closures (Cauchy-robustified, σ from the file).",
                     "seed 000 Eq. (1), L_pq", kOdometry)),
          odometry_noise("odometry_sigma_translation_m", &Noise::sigma_translation_m,
                         greater_than(0),
                         doc("m",
                             "> 0: recorded odometry: σ_t = this + "
                             "`odometry_sigma_translation_per_m` · |t_ij| (m, per axis)",
                             "beyond the paper: recorded odometry carries no covariance (LVI-SAM "
                             "takes it from scan matching)",
                             kOdometry)),
          odometry_noise(
              "odometry_sigma_translation_per_m", &Noise::sigma_translation_per_m, at_least(0),
              doc("m/m", "≥ 0: m of σ per m travelled (1 % of distance)", kAsAbove, kOdometry)),
          odometry_noise(
              "odometry_sigma_rotation_rad", &Noise::sigma_rotation_rad, greater_than(0),
              doc("rad",
                  "> 0: recorded odometry: σ_φ = this + `odometry_sigma_rotation_per_rad` "
                  "· |φ_ij| + 0.001 rad/m · |t_ij| (rad, per axis; the per-metre term is "
                  "fixed in `slam::OdometryNoise`)",
                  kAsAbove, kOdometry)),
          odometry_noise("odometry_sigma_rotation_per_rad", &Noise::sigma_rotation_per_rad,
                         at_least(0),
                         doc("rad/rad", "≥ 0: rad of σ per rad turned", kAsAbove, kOdometry)),
          option("odometry_noise_from_map", &O::odometry_noise_from_map,
                 doc("",
                     "widen every odometry edge's variance, per axis, by the squared RMS "
                     "disagreement between the odometry increments and the MAP poses' increments "
                     "(reported as `inputs.odometry.disagreement_with_map_rms`). Applies to "
                     "recorded and GICP odometry alike (GICP's point-to-plane information is far "
                     "too confident)",
                     "beyond the paper: a per-mission variance estimate, so a degenerated odometry "
                     "(corridor) stops outvoting the DVL",
                     kOdometry)),
          option(
              "degeneracy", &O::degeneracy, one_of({"drop", "keep_well_conditioned", "ignore"}),
              doc("",
                  "`drop`, `keep_well_conditioned` or `ignore`: what to do with an odometry edge "
                  "flagged degenerate: drop it (the keyframe rests on IMU and DVL), keep only "
                  "its well-observed directions, or keep it whole (flag only)",
                  "`drop` is seed 000 Sec. IV-B; the other two are ours", kDegeneracy)),
          option("degeneracy_sigma_translation_m", &O::degeneracy_sigma_translation_m,
                 greater_than(0),
                 doc("m",
                     "> 0: a translation direction of an edge is degenerate when its σ (after "
                     "`odometry_noise_from_map`) exceeds this, m (eigenvalue of the information "
                     "below 1/σ²)",
                     "beyond the paper (the paper's detector is LVI-SAM's): 0.2 m is a fifth of a "
                     "~1 m keyframe step",
                     kDegeneracy)),
          option("degeneracy_sigma_rotation_rad", &O::degeneracy_sigma_rotation_rad,
                 greater_than(0),
                 doc("rad", "> 0: the same for rotation, rad", kBeyond, kDegeneracy)),
          option(
              "imu_position_when_degenerate", &O::imu_position_when_degenerate,
              doc("",
                  "over degenerate intervals keep I_ij's position residual next to D_ij "
                  "(elsewhere it is zero-weighted where D_ij exists, as in the paper); this "
                  "makes s_d observable along the degenerate axis. false: the paper's rule "
                  "everywhere (residual dropped). The biases of degenerate keyframes are zeroed "
                  "and held (the paper's rule) only when nothing makes them observable: neither "
                  "this residual with a DVL nor MAP anchors",
                  "beyond the paper; the rule it departs from is seed 000 Sec. IV-B", kDegeneracy)),
          option(
              "map_anchors", &O::map_anchors,
              doc("",
                  "anchor every keyframe to its recorded MAP pose (`slam::MapAnchorFactor`): "
                  "its position error is white noise plus a drift state that random-walks along "
                  "the path travelled while the odometry is degenerate, its rotation error "
                  "white; Huber-robustified (1.345 whitened). The first keyframe's anchor (drift "
                  "zero) replaces the pose part of r_0",
                  "beyond the paper: offline, the online SLAM's global constraints "
                  "(scan-to-map, its loops) survive only in its MAP poses; without anchors "
                  "nothing bounds the heading drift of odometry + IMU + DVL dead reckoning. The "
                  "error model is the online SLAM's: it dead reckons along what its scan "
                  "matching cannot see",
                  kOdometry)),
          option("map_sigma_translation_m", &O::map_sigma_translation_m, greater_than(0),
                 doc("m",
                     "> 0: MAP white position σ, m per axis: the first solve's (the value used "
                     "throughout when not estimated)",
                     kBeyond, kOdometry)),
          option("map_sigma_rotation_rad", &O::map_sigma_rotation_rad, greater_than(0),
                 doc("rad", "> 0: MAP rotation σ, rad per axis, likewise", kBeyond, kOdometry)),
          option("map_drift_per_sqrt_m", &O::map_drift_per_sqrt_m, greater_than(0),
                 doc("m/√m", "> 0: MAP drift random walk, m per √m of degenerate path, likewise",
                     kBeyond, kOdometry)),
          option("estimate_map_noise", &O::estimate_map_noise,
                 doc("",
                     "estimate the MAP noise from the data (`slam::estimate_map_pose_noise`): "
                     "after each solve but the last, the white covariance, the drift covariance "
                     "per metre (full 3x3, world axes) and the rotation covariance are fitted to "
                     "the differences of (MAP - refined) over lags of 1-5 keyframes; the next "
                     "solve uses them. Reported as `map_noise`. false: the three options above, "
                     "as given",
                     "beyond the paper: the recorded poses carry no covariance", kOdometry)),
          option("gnss", &O::gnss,
                 doc("",
                     "add a position factor per GNSS fix (`slam::GnssPositionFactor`: the antenna "
                     "at T_body_sensor, interpolated between the keyframes around the fix; "
                     "covariance from the fix, else the sensor's `noise`). No-fix messages "
                     "(status -1) are counted and left out. With 3 or more fixes r_0 keeps no "
                     "pose part: the fixes place the trajectory in the world frame, which "
                     "mission.yaml's `origin` makes the local ENU frame",
                     "beyond the paper (issue 30)", kGnss)),
          option("gnss_sensor", &O::gnss_sensor,
                 doc("", "GNSS whose fixes make the factors", "", kGnss, "`\"\"` = first `gnss`")),
          option("gnss_gate_chi2", &O::gnss_gate_chi2, greater_than(0),
                 doc("",
                     "> 0: a fix whose squared Mahalanobis distance (3 dof, its covariance) to "
                     "the previous pass's estimate exceeds this is left out and counted "
                     "(`gnss.rejected`); the first pass keeps every fix under a Cauchy loss. "
                     "16.266 = chi-square 3 dof at p = 0.999",
                     "beyond the paper: a reflected fix under a bridge is metres off, status 0",
                     kGnss)),
          option("gnss_min_sigma_m", &O::gnss_min_sigma_m, greater_than(0),
                 doc("m", "> 0: floor on a fix's sigma per axis, m (RTK fixes claim mm)", kBeyond,
                     kGnss)),
          option("max_iterations", &O::max_iterations, int_in_range(1, 10000),
                 doc("", "in [1, 10000]: Ceres iterations per pass", "", kSolver)),
          option("relinearization_passes", &O::relinearization_passes, int_in_range(1, 10),
                 doc("",
                     "in [1, 10]: solve, re-preintegrate at the new biases / s_d / extrinsic, "
                     "solve again; "
                     "keeps the first-order corrections (Eq. (27), [27] Eq. (44)) small",
                     "", kSolver)),
          option("threads", &O::threads, int_in_range(1, 256),
                 doc("",
                     "in [1, 256]: threads of the covariances' columns; the Ceres solve runs on "
                     "one thread whatever this is (on several, Ceres sums the residual blocks in "
                     "the order its threads take them and the reported costs changed with the "
                     "thread count), so the outputs are the same to the bit on any number of "
                     "threads",
                     "", kSolver)),
          option("compare_without_dvl", &O::compare_without_dvl,
                 doc("",
                     "with `dvl` and ground truth, solve a second time without DVL so the report "
                     "sets MAP / without DVL / with DVL side by side (`trajectory_refined.tum` is "
                     "the DVL solve)",
                     "seed 000 Table II", kEvaluation)),
          option("ate_max_time_difference_s", &O::ate_max_time_difference_s, at_least(0),
                 doc("s",
                     "≥ 0: poses are associated with ground truth by nearest stamp within this, s "
                     "(evo's `--t_max_diff`); ATE after SE(3) Umeyama alignment",
                     "evo", kEvaluation)),
          option("rpe_delta_m", &O::rpe_delta_m, greater_than(0),
                 doc("m", "> 0: RPE over pose pairs this far apart along the ground-truth path, m",
                     "evo (`--delta_unit m`)", kEvaluation)),
      });
  return table;
}

// The options report.json echoes: the main switches and sigmas.
// clang-format off
constexpr const char* kReported[] = {
    "dvl", "estimate_dvl_scale", "estimate_dvl_rotation", "odometry", "loop_closures",
    "odometry_noise_from_map", "degeneracy", "degeneracy_sigma_translation_m",
    "degeneracy_sigma_rotation_rad", "imu_position_when_degenerate", "map_anchors",
    "map_sigma_translation_m", "map_sigma_rotation_rad", "map_drift_per_sqrt_m",
    "estimate_map_noise", "max_dvl_gap_s", "servo_window_s", "rpe_delta_m"};
// clang-format on

}  // namespace

RefineStageOptions RefineStageOptions::from_json(const nlohmann::json& options) {
  return table().from_json(options);
}

nlohmann::json RefineStageOptions::report_json() const {
  const nlohmann::ordered_json all = table().to_json(*this);
  nlohmann::json out = nlohmann::json::object();
  for (const char* name : kReported) out[name] = all.at(name);
  return out;
}

const OptionsSchema& RefineStage::options() const { return table(); }

}  // namespace keel::pipeline
