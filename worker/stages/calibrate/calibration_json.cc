#include "worker/stages/calibrate/calibration_json.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace keel::pipeline {
namespace {

using nlohmann::json;

constexpr double kDeg = 180.0 / M_PI;

json vector_json(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

std::string triple(const Eigen::Vector3d& v) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.3f, %.3f, %.3f)", v.x(), v.y(), v.z());
  return text;
}

// {"xyz_m": .., "rpy_deg": ..} in the contract's order, for people to read and paste.
std::string ordered_dump(const json& pose) {
  nlohmann::ordered_json out;
  out["xyz_m"] = pose.at("xyz_m");
  out["rpy_deg"] = pose.at("rpy_deg");
  return out.dump();
}

}  // namespace

json human_pose(const Pose3& T) {
  const Eigen::Matrix3d R = T.linear();
  // Fixed-axis X-Y-Z (ROS/URDF): R = Rz(yaw) Ry(pitch) Rx(roll).
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  return {{"xyz_m", vector_json(T.translation())},
          {"rpy_deg", json::array({roll * kDeg, pitch * kDeg, yaw * kDeg})}};
}

std::string describe_direction(const mapping::Vector6d& direction,
                               const Pose3& T_reference_candidate, const std::string& reference) {
  // The perturbation acts in the candidate frame; its axes are turned into the reference's.
  const Eigen::Matrix3d R = T_reference_candidate.linear();
  const Eigen::Vector3d t = R * direction.head<3>();
  const Eigen::Vector3d phi = R * direction.tail<3>();
  const std::string axes = reference + "'s axes ";
  if (phi.norm() < 0.1) return "translation along " + triple(t.normalized()) + " of " + axes;
  if (t.norm() < 0.1) return "rotation about " + triple(phi.normalized()) + " of " + axes;
  return "translation " + triple(t) + " (m) with rotation " + triple(phi) + " (rad) in " + axes;
}

json residuals_json(const mapping::ResidualSummary& s) {
  return {{"points", s.points},
          {"matched", s.matched},
          {"median_m", s.median_m},
          {"p90_m", s.p90_m},
          {"rms_m", s.rms_m},
          {"histogram", {{"edges_m", s.histogram_edges_m}, {"counts", s.histogram_counts}}}};
}

json candidate_json(const CalibrationSensor& reference, const CandidateOutcome& c) {
  const mapping::ExtrinsicRefinementResult& r = c.result;
  json out = {{"sensor", c.sensor.name},
              {"type", c.sensor.type},
              {"status", r.refused ? "refused" : "refined"}};
  if (r.refused) out["reason"] = r.reason;
  out["initial"] = {{"T_reference_candidate", human_pose(c.T_reference_candidate_initial)},
                    {"T_body_sensor", human_pose(c.sensor.T_body_sensor)},
                    {"source", c.sensor.source}};
  out["residuals"] = {{"before", residuals_json(r.before)}};
  out["reference_map"] = {{"points", r.reference_points}, {"planar", r.reference_planar}};
  if (r.refused) return out;

  out["refined"] = {
      {"T_reference_candidate", human_pose(r.T_reference_candidate)},
      {"T_body_sensor", human_pose(reference.T_body_sensor * r.T_reference_candidate)}};
  json covariance = json::array();
  for (int i = 0; i < 6; ++i) {
    json row = json::array();
    for (int j = 0; j < 6; ++j) row.push_back(r.covariance(i, j));
    covariance.push_back(row);
  }
  out["covariance"] = covariance;
  const mapping::Vector6d sigma = r.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  out["sigma"] = {{"xyz_m", vector_json(sigma.head<3>())},
                  {"rpy_deg", vector_json(sigma.tail<3>() * kDeg)}};
  json unobservable = json::array();
  for (const auto& u : r.unobservable) {
    json direction = json::array();
    for (int i = 0; i < 6; ++i) direction.push_back(u.direction(i));
    unobservable.push_back({{"direction", direction},
                            {"eigenvalue", u.eigenvalue},
                            {"ratio", u.ratio},
                            {"description", describe_direction(u.direction, r.T_reference_candidate,
                                                               reference.name)}});
  }
  out["unobservable"] = unobservable;
  out["information"] = {{"rotation_scale_m", r.rotation_scale_m},
                        {"eigenvalues", std::vector<double>(r.information_eigenvalues.data(),
                                                            r.information_eigenvalues.data() + 6)}};
  out["residuals"]["after"] = residuals_json(r.after);
  out["residual_sigma_m"] = r.residual_sigma_m;
  out["iterations"] = r.iterations;
  out["converged"] = r.converged;
  out["metrics"] = {{"before", c.metrics_before}, {"after", c.metrics_after}};
  json warnings = json::array();
  if (!r.converged)
    warnings.push_back("did not converge in " + std::to_string(r.iterations) +
                       " iterations: the scene may not constrain " + c.sensor.name + " against " +
                       reference.name +
                       "; check the unobservable directions and the residuals before using it");
  if (r.after.median_m > r.before.median_m)
    warnings.push_back("the median residual grew (" + std::to_string(r.before.median_m) + " -> " +
                       std::to_string(r.after.median_m) + " m)");
  out["warnings"] = warnings;

  const std::string key = "T_" + reference.name + "_" + c.sensor.name;
  const json pose = human_pose(r.T_reference_candidate);
  out["reprocess"] = {{"options", {{"calibration", {{c.sensor.name, {{key, pose}}}}}}},
                      {"set", json::array({"calibration." + c.sensor.name + "." + key + "=" +
                                           ordered_dump(pose)})}};
  return out;
}

}  // namespace keel::pipeline
