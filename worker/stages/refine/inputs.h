// The solver's inputs, read from the mission (steps 2-5 of stage.cc), and what the report says
// of them (its `inputs` section).
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "core/pose.h"
#include "core/time.h"
#include "proto/mission_manifest.h"
#include "worker/io/mission_reader.h"
#include "worker/pipeline/stage.h"
#include "worker/slam/refine_solver.h"
#include "worker/stages/refine/options.h"

namespace keel::pipeline {

struct Inputs {
  slam::RefineInput solver;
  nlohmann::json report = nlohmann::json::object();
  nlohmann::json warnings = nlohmann::json::array();
  std::string dvl_sensor;                         // empty without DVL fusion
  Pose3 T_body_dvl_manifest = Pose3::Identity();  // the DVL rotation's starting value
  // GNSS (gnss_inputs.cc): the sensor used (empty: none) and, per fix given to the solver,
  // its stamp; fixes read without a position (status -1).
  std::string gnss_sensor;
  size_t gnss_no_fix = 0;
};

// Step 2 (inputs.cc): the recorded `map` poses as keyframes (stamps and initial values).
Inputs recorded_keyframes(const io::MissionReader& reader);

// Step 3 (inertial_inputs.cc): IMU and, with DVL fusion, DVL samples with their extrinsics and
// noise figures (into `solver_options`); a DVL on a servo tray turned into its angle-0 frame.
void inertial_inputs(const io::MissionReader& reader, const RefineStageOptions& options,
                     slam::RefineOptions& solver_options, Inputs& in);

// Step 4 (odometry_edges.cc): the odometry edges, recorded or GICP as `options.odometry` says;
// keyframes without odometry are dropped.
void odometry_edges(const io::MissionReader& reader, const RefineStageOptions& options,
                    const slam::RefineOptions& solver_options, StageContext& context, Inputs& in);

// Step 5 (loop_closures.cc): the loop closures whose stamps both match a keyframe.
void loop_closures(const io::MissionReader& reader, const RefineStageOptions& options,
                   const slam::RefineOptions& solver_options, Inputs& in);

// Step 5b (gnss_inputs.cc): the GNSS fixes in the world (ENU) frame with their covariance and
// the antenna's lever arm, when the mission has a gnss sensor and `options.gnss`.
void gnss_inputs(const io::MissionReader& reader, const RefineStageOptions& options, Inputs& in);
// report.json `gnss` (null without GNSS): counts of fixes used, rejected by the gate, without a
// fix, outside the keyframes, the rejected fixes' stamps, the origin and the options used.
nlohmann::json gnss_report_json(const slam::RefineResult& result, const Inputs& in,
                                const RefineStageOptions& options,
                                const proto::MissionManifest& manifest);

// ---- shared by the steps above (inputs.cc) ------------------------------------------------

// The sensor named by `chosen` (option `option`), else the first of `type`; nullptr when the
// mission has none.
const proto::SensorSpec* pick_sensor(const proto::MissionManifest& manifest,
                                     const std::string& chosen, proto::SensorType type,
                                     const std::string& option);
// {t_first_s, t_last_s, duration_s}.
nlohmann::json span_json(TimeNs first, TimeNs last);
// Index of the keyframe within `tolerance` of t_ns (the nearest), or -1.
long find_keyframe(const Trajectory& keyframes, TimeNs t_ns, TimeNs tolerance);
// The keyframes for which keep[k] is true.
Trajectory select(const Trajectory& keyframes, const std::vector<bool>& keep);
// Fails unless at least 2 keyframes are left (`why` says which).
void require_keyframes(const Trajectory& keyframes, const std::string& why);

}  // namespace keel::pipeline
