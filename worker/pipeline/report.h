// report.json: every figure the stages measured, in one document.
//
//   {"keel_report": 1,
//    "job": {...}, "mission": {...},
//    "calibration": {"lidar_v": {"source": "mission.yaml", "T_body_sensor": {...}, ...}},
//    "stages": {"ingest": {...}, "refine": {...}},   // in pipeline order
//    "stage_seconds": {"ingest": 0.41, ...},
//    "failed": {"stage": "map", "error": "..."}}      // only when the job failed
//
// Keys keep this order in the file (ordered_json) so people can read it top to bottom.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace keel::pipeline {

inline constexpr int kReportVersion = 1;
inline constexpr const char* kReportFileName = "report.json";

struct ReportInput {
  nlohmann::json job = nlohmann::json::object();      // id, stages, options, ...
  nlohmann::json mission = nlohmann::json::object();  // id, name, blobs or local paths
  // Per sensor with an extrinsic, the one the job used and its source (job_extrinsics.h's
  // calibration_report); null when the mission could not be read.
  nlohmann::json calibration = nullptr;
  std::vector<std::string> stage_order;              // the job's stages, in order
  nlohmann::json stages = nlohmann::json::object();  // stage name -> its report section
  std::map<std::string, double> stage_seconds;
  // A failed job's report: {"stage", "error"}; stage_order then lists the stages that finished.
  nlohmann::json failure = nullptr;
};

// Fails (std::invalid_argument naming the stage) when a stage of stage_order has no section,
// a section is not an object, or a section/duration belongs to no stage of stage_order.
nlohmann::ordered_json build_report(const ReportInput& input);

// Writes `document` (pretty-printed) to `path` atomically (core/replaced_file.h: a temporary
// sibling renamed over `path`). Throws std::runtime_error naming the file.
void write_json_atomically(const std::filesystem::path& path,
                           const nlohmann::ordered_json& document);

// Writes report.json and report.html (render_report_html, with the work folder's
// trajectories.json when one parses) into `work_dir`; returns their file names. Throws
// std::runtime_error naming the file that could not be written. (report_html.cc: it asks
// every stage for its section, so it lives with the registry in keel_pipeline.)
std::vector<std::string> write_report_files(const std::filesystem::path& work_dir,
                                            const nlohmann::ordered_json& report);

}  // namespace keel::pipeline
