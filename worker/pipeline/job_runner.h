// Runs a job's stages in order over one work folder. Knows nothing of HTTP: `keel-worker`
// (leased from a server) and `keel-worker run` (local) both drive it through JobHooks.
//
// Steps of JobRunner::run:
//   0. the extrinsics the stages will use (the job's `calibration` overrides applied,
//      job_extrinsics.h), for report.json's `calibration` section;
//   1. build every stage object first, so an unknown stage fails before any work is done;
//   2. skip the stages completed earlier (their reports are given, their artifacts are
//      already in work_dir);
//   3. run each remaining stage with its options and the reports of the stages before it,
//      timing it and forwarding its progress (monotone, in [0, 1]) and log lines;
//   4. a std::exception thrown by a stage ends the job as failed with "<stage>: <what()>";
//      Canceled (or hooks.canceled() turning true) ends it as canceled;
//   5. report.json and report.html of every finished stage (and a failed job's error) are
//      written into work_dir, for `keel-worker serve` and `keel-worker run` alike. After the
//      last stage they are among its artifacts (so they are uploaded with them); otherwise
//      JobResult::report_files names them.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "worker/pipeline/stage.h"

namespace keel::pipeline {

// A stage finished by an earlier attempt of the same job.
struct CompletedStage {
  std::string stage;
  nlohmann::json report = nlohmann::json::object();
  double seconds = 0.0;
};

struct JobSpec {
  std::filesystem::path mission_dir;  // holds mission.yaml
  std::filesystem::path cad_path;     // empty when the mission has no CAD mesh
  std::filesystem::path work_dir;     // created when missing
  std::vector<std::string> stages;    // in the order to run
  // {"stage": {"option": value}, "calibration": {...}} (the overrides: docs/calibration.md)
  nlohmann::json options = nlohmann::json::object();
  std::vector<CompletedStage> completed;          // skipped; reports passed on
  std::vector<InputJob> input_jobs;               // the jobs a `compare` stage reads
  nlohmann::json job = nlohmann::json::object();  // the job's own record (a lease's)
  // What report.json says of the job ({"id", "stages", "options", ...}) and of its mission
  // ({"id", "name", ...} or {"path", "cad"}).
  nlohmann::json report_job = nlohmann::json::object();
  nlohmann::json report_mission = nlohmann::json::object();
};

// Every hook is optional. They are called on the thread that calls run(). An exception
// thrown by a hook is not a stage failure: it propagates out of run().
struct JobHooks {
  std::function<void(const std::string& stage)> on_stage_start;
  std::function<void(const std::string& stage, const StageResult& result, double seconds)>
      on_stage_done;
  std::function<void(const std::string& stage, double progress)> progress;  // non-decreasing
  std::function<void(const std::string& line)> log;
  std::function<bool()> canceled;  // polled by stages through StageContext::check_canceled
};

enum class JobOutcome { kSucceeded, kFailed, kCanceled };
std::string to_string(JobOutcome outcome);

struct JobResult {
  JobOutcome outcome = JobOutcome::kSucceeded;
  std::string error;         // "<stage>: <message>" when failed
  std::string failed_stage;  // the stage that failed or was canceled
  // Report sections and durations of every finished stage (earlier attempts included).
  nlohmann::json reports = nlohmann::json::object();
  std::map<std::string, double> stage_seconds;
  std::vector<std::string> ran;  // stages run (not skipped) by this call, in order
  // report.json and report.html when they were written and are not among the last stage's
  // artifacts (a failed job; a job whose stages were all finished earlier); `report_error`
  // says why they could not be written (the job's outcome stands).
  std::vector<std::string> report_files;
  std::string report_error;
};

// The `calibration` object of a job's options (docs/calibration.md), null when absent.
const nlohmann::json& job_calibration(const nlohmann::json& options);

using StageFactory = std::function<std::unique_ptr<Stage>(const std::string& name)>;

class JobRunner {
 public:
  // `factory` defaults to make_stage (the stages built into this worker).
  explicit JobRunner(StageFactory factory = {});
  JobResult run(const JobSpec& spec, const JobHooks& hooks = {}) const;

 private:
  StageFactory factory_;
};

}  // namespace keel::pipeline
