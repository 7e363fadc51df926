// calibration.json (docs/calibration.md, section 2): per candidate, the initial and refined
// T_reference_candidate, covariance, sigmas, unobservable directions in words, residuals and
// map metrics before and after, and the reprocess override it offers (never applied here).
#pragma once

#include <nlohmann/json.hpp>

#include <string>

#include "core/pose.h"
#include "worker/mapping/extrinsic_refinement.h"
#include "worker/mapping/map_metrics.h"
#include "worker/stages/calibrate/sensors.h"

namespace keel::pipeline {

// {"xyz_m": [x, y, z], "rpy_deg": [roll, pitch, yaw]}, R = Rz(yaw) Ry(pitch) Rx(roll).
nlohmann::json human_pose(const Pose3& T);

// `direction` [x y z roll pitch yaw] of the right perturbation of T_reference_candidate, in
// words, in the reference sensor's axes: "translation along lidar_h's (0.999, 0.02, 0.00)".
std::string describe_direction(const mapping::Vector6d& direction,
                               const Pose3& T_reference_candidate, const std::string& reference);

nlohmann::json residuals_json(const mapping::ResidualSummary& summary);

struct CandidateOutcome {
  CalibrationSensor sensor;
  Pose3 T_reference_candidate_initial = Pose3::Identity();
  mapping::ExtrinsicRefinementResult result;
  nlohmann::json metrics_before = nullptr, metrics_after = nullptr;  // mapping::to_json
  double seconds = 0.0;  // report.json's timing only: calibration.json stays deterministic
};

nlohmann::json candidate_json(const CalibrationSensor& reference, const CandidateOutcome& c);

}  // namespace keel::pipeline
