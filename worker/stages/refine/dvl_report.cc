#include "worker/stages/refine/dvl_report.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <optional>

#include "worker/io/display_path.h"
#include "worker/io/yaml_json.h"
#include "worker/slam/so3.h"

namespace keel::pipeline {

namespace {

using nlohmann::json;

constexpr double kRadToDeg = 180.0 / M_PI;

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
                      const Pose3& T_body_dvl_manifest, const DvlTruth& truth) {
  json scale = {{"estimated", options.estimate_dvl_scale},
                {"value", r.dvl_scale},
                {"sigma", r.dvl_scale_sigma},
                {"true", truth.scale ? json(*truth.scale) : json(nullptr)}};
  const Eigen::Matrix3d R_est = r.q_body_dvl.toRotationMatrix();
  const Eigen::Matrix3d& R_init = T_body_dvl_manifest.linear();
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

}  // namespace

json dvl_report_json(const slam::RefineResult& with_dvl, const RefineStageOptions& options,
                     const io::Mission& mission, Inputs& in) {
  const DvlTruth truth = read_dvl_truth(mission, in.dvl_sensor, in.warnings);
  json out = calibration_json(with_dvl, options, in.T_body_dvl_manifest, truth);
  out["gaps"] = dvl_gaps(in.solver.dvl, options.max_dvl_gap_s);
  out["gaps"]["intervals_without_dvl_factor"] = with_dvl.summary.num_dvl_intervals_skipped;
  return out;
}

}  // namespace keel::pipeline
