#include "worker/pipeline/job_runner.h"

#include <chrono>
#include <cmath>
#include <exception>
#include <set>
#include <sstream>
#include <utility>

#include "proto/calibration.h"
#include "worker/io/display_path.h"
#include "worker/pipeline/job_extrinsics.h"
#include "worker/pipeline/report.h"
#include "worker/pipeline/report_html.h"

namespace keel::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

std::string format_seconds(double seconds) {
  std::ostringstream out;
  out.precision(3);
  out << std::fixed << seconds;
  return out.str();
}

// An artifact name must be a plain file name in work_dir: no folders, no "..".
bool is_plain_file_name(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
         name.find('\\') == std::string::npos && name.find('\0') == std::string::npos;
}

// Checks what a stage returned: every artifact it names exists in work_dir.
void check_artifacts(const StageResult& result, const std::filesystem::path& work_dir) {
  if (!result.report.is_object()) throw std::runtime_error("report section is not a JSON object");
  for (const auto& name : result.artifacts) {
    if (!is_plain_file_name(name))
      throw std::runtime_error("artifact name '" + name + "' is not a plain file name");
    std::error_code ec;
    if (!std::filesystem::is_regular_file(work_dir / name, ec))
      throw std::runtime_error("artifact '" + name + "' was not written to " + work_dir.string());
  }
}

// Forwards a stage's progress clamped to [0, 1] and never decreasing, so observers see a
// monotone figure even when a stage's estimate wobbles.
class ProgressForwarder {
 public:
  ProgressForwarder(const JobHooks& hooks, std::string stage)
      : hooks_(hooks), stage_(std::move(stage)) {}
  void operator()(double value) {
    if (std::isnan(value)) return;
    value = std::min(1.0, std::max(0.0, value));
    if (reported_ && value <= last_) return;
    last_ = value;
    reported_ = true;
    if (hooks_.progress) hooks_.progress(stage_, value);
  }

 private:
  const JobHooks& hooks_;
  std::string stage_;
  double last_ = 0.0;
  bool reported_ = false;
};

// report.json of the stages finished so far (in the job's order) and, for a failed job, its
// error; written with report.html into work_dir. Returns the file names.
std::vector<std::string> write_report(const JobSpec& spec, const JobResult& result,
                                      const nlohmann::json& calibration) {
  ReportInput input;
  input.job = spec.report_job;
  input.mission = spec.report_mission;
  input.calibration = calibration;
  input.stages = result.reports;
  input.stage_seconds = result.stage_seconds;
  for (const auto& stage : spec.stages)
    if (result.reports.contains(stage)) input.stage_order.push_back(stage);
  if (result.outcome == JobOutcome::kFailed)
    input.failure = {{"stage", result.failed_stage}, {"error", result.error}};
  return write_report_files(spec.work_dir, build_report(input));
}

// The job's extrinsics and their sources for report.json, or null when the mission cannot be
// read with them: then the first stage that reads it fails with the reason (a bad override
// names its option path there).
nlohmann::json calibration_section(const JobSpec& spec) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(spec.mission_dir / "mission.yaml", ec)) return nullptr;
  try {
    return calibration_report(
        job_extrinsics(load_job_mission(spec.mission_dir, job_calibration(spec.options))));
  } catch (const std::exception&) {
    return nullptr;
  }
}

}  // namespace

const nlohmann::json& job_calibration(const nlohmann::json& options) {
  static const nlohmann::json none = nullptr;
  if (!options.is_object()) return none;
  const auto it = options.find(proto::kCalibrationOption);
  return it == options.end() ? none : *it;
}

std::string to_string(JobOutcome outcome) {
  switch (outcome) {
    case JobOutcome::kSucceeded:
      return "succeeded";
    case JobOutcome::kFailed:
      return "failed";
    case JobOutcome::kCanceled:
      return "canceled";
  }
  return "unknown";
}

JobRunner::JobRunner(StageFactory factory) : factory_(std::move(factory)) {
  if (!factory_) factory_ = [](const std::string& name) { return make_stage(name); };
}

JobResult JobRunner::run(const JobSpec& spec, const JobHooks& hooks) const {
  JobResult result;
  auto log = [&](const std::string& line) {
    if (hooks.log) hooks.log(line);
  };
  auto canceled = [&] { return hooks.canceled && hooks.canceled(); };
  // 0. The extrinsics every stage will use, for report.json.
  const nlohmann::json calibration = calibration_section(spec);
  // 5. report.json and report.html, outside the last stage's artifacts.
  auto report_aside = [&] {
    try {
      result.report_files = write_report(spec, result, calibration);
    } catch (const std::exception& e) {
      result.report_error = e.what();
    }
  };
  auto fail = [&](const std::string& stage, const std::string& message) {
    result.outcome = JobOutcome::kFailed;
    result.failed_stage = stage;
    result.error = stage + ": " + message;
    log("failed: " + result.error);
    report_aside();
    return result;
  };

  std::set<std::string> done;
  bool report_with_last_stage = false;
  for (const auto& completed : spec.completed) {
    result.reports[completed.stage] = completed.report;
    result.stage_seconds[completed.stage] = completed.seconds;
    done.insert(completed.stage);
  }

  // 1. Build every pending stage before running any.
  std::vector<std::unique_ptr<Stage>> stages(spec.stages.size());
  for (size_t i = 0; i < spec.stages.size(); ++i) {
    if (done.count(spec.stages[i])) continue;
    try {
      stages[i] = factory_(spec.stages[i]);
    } catch (const std::exception& e) {
      return fail(spec.stages[i], e.what());
    }
    if (!stages[i]) return fail(spec.stages[i], "no such stage in this worker");
  }

  std::error_code ec;
  std::filesystem::create_directories(spec.work_dir, ec);
  if (ec)
    return fail(spec.stages.empty() ? "job" : spec.stages.front(),
                "cannot create work folder " + spec.work_dir.string() + ": " + ec.message());

  for (size_t i = 0; i < stages.size(); ++i) {
    const std::string& name = spec.stages[i];
    // 2. Skip what an earlier attempt finished.
    if (done.count(name)) {
      log(name + ": completed earlier, skipped");
      continue;
    }
    if (canceled()) {
      result.outcome = JobOutcome::kCanceled;
      result.failed_stage = name;
      log(name + ": canceled before start");
      return result;
    }

    // 3. Run it.
    StageContext context;
    context.mission_dir = spec.mission_dir;
    context.cad_path = spec.cad_path;
    context.work_dir = spec.work_dir;
    context.input_jobs = spec.input_jobs;
    context.job = spec.job;
    if (spec.options.is_object() && spec.options.contains(name))
      context.options = spec.options.at(name);
    context.calibration = job_calibration(spec.options);
    context.reports = result.reports;
    ProgressForwarder progress(hooks, name);
    context.progress = [&progress](double value) { progress(value); };
    context.log = [&log, &name](const std::string& line) { log(name + ": " + line); };
    context.canceled = canceled;

    if (hooks.on_stage_start) hooks.on_stage_start(name);
    log(name + ": started");
    progress(0.0);
    const auto start = Clock::now();
    StageResult stage_result;
    try {
      // Errors name the user's files as in their bundle, not this worker's copy of it.
      const io::DisplayRoots roots({spec.mission_dir, spec.cad_path});
      stage_result = stages[i]->run(context);
      check_artifacts(stage_result, spec.work_dir);
    } catch (const Canceled&) {
      result.outcome = JobOutcome::kCanceled;
      result.failed_stage = name;
      log(name + ": canceled");
      return result;
    } catch (const std::exception& e) {
      // 4. The stage's own message, verbatim, after its name.
      return fail(name, e.what());
    } catch (...) {
      return fail(name, "unknown error (not a std::exception)");
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    // A cancel that arrived while the stage finished: report nothing more.
    if (canceled()) {
      result.outcome = JobOutcome::kCanceled;
      result.failed_stage = name;
      log(name + ": canceled");
      return result;
    }
    progress(1.0);
    result.reports[name] = stage_result.report;
    result.stage_seconds[name] = seconds;
    result.ran.push_back(name);
    log(name + ": done in " + format_seconds(seconds) + " s");
    // 5. After the last stage, the report is among its artifacts.
    if (i + 1 == stages.size()) {
      try {
        for (auto& file : write_report(spec, result, calibration))
          stage_result.artifacts.push_back(file);
        report_with_last_stage = true;
      } catch (const std::exception& e) {
        return fail(name, e.what());
      }
    }
    if (hooks.on_stage_done) hooks.on_stage_done(name, stage_result, seconds);
  }
  // Every stage was finished by an earlier attempt (or none was asked for).
  if (!report_with_last_stage) report_aside();
  return result;
}

}  // namespace keel::pipeline
