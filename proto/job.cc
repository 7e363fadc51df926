#include "proto/job.h"

#include <algorithm>

#include "proto/auth.h"
#include "proto/contract_error.h"
#include "proto/options.h"

namespace keel::proto {

namespace {
constexpr std::pair<JobState, const char*> kStateNames[] = {{JobState::kQueued, "queued"},
                                                            {JobState::kRunning, "running"},
                                                            {JobState::kSucceeded, "succeeded"},
                                                            {JobState::kFailed, "failed"},
                                                            {JobState::kCanceled, "canceled"}};
}  // namespace

std::string to_string(JobState state) {
  for (const auto& [value, name] : kStateNames)
    if (value == state) return name;
  return "unknown";
}

JobState job_state_from_string(std::string_view text, const std::string& path) {
  for (const auto& [value, name] : kStateNames)
    if (text == name) return value;
  throw ContractError(path + ": unknown job state '" + std::string(text) +
                      "' (expected queued, running, succeeded, failed or canceled)");
}

bool is_terminal(JobState state) {
  return state == JobState::kSucceeded || state == JobState::kFailed ||
         state == JobState::kCanceled;
}

nlohmann::json JobRequest::to_json() const {
  nlohmann::json out = {{"mission_id", mission_id}, {"stages", stages}, {"options", options}};
  if (!project.empty()) out["project"] = project;
  return out;
}

namespace {
std::string optional_project(const FieldReader& r) {
  std::string project = r.optional<std::string>("project", "");
  if (!project.empty()) validate_project_name(project, r.child("project"));
  return project;
}

nlohmann::json state_counts(const std::map<std::string, int64_t>& counts) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [state, name] : kStateNames) {
    auto it = counts.find(name);
    out[name] = it == counts.end() ? 0 : it->second;
  }
  return out;
}
}  // namespace

JobRequest JobRequest::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"mission_id", "stages", "options", "project"});
  JobRequest out;
  out.mission_id = r.required<std::string>("mission_id");
  out.project = optional_project(r);
  out.stages = r.required<std::vector<std::string>>("stages");
  validate_stage_list(out.stages, r.child("stages"));
  out.options = r.optional<nlohmann::json>("options", nlohmann::json::object());
  validate_options(out.options, r.child("options"));
  return out;
}

nlohmann::json Job::to_json() const {
  return {{"id", id},
          {"mission_id", mission_id},
          {"state", to_string(state)},
          {"stages", stages},
          {"options", options},
          {"stage", stage},
          {"progress", progress},
          {"completed_stages", completed_stages},
          {"stage_seconds", stage_seconds},
          {"error", error},
          {"attempts", attempts},
          {"created_at_ms", created_at_ms},
          {"started_at_ms", started_at_ms},
          {"finished_at_ms", finished_at_ms},
          {"project", project},
          {"batch_id", batch_id},
          {"worker", worker},
          {"mission_name", mission_name}};
}

Job Job::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"id", "mission_id", "state", "stages", "options", "stage", "progress",
                    "completed_stages", "stage_seconds", "error", "attempts", "created_at_ms",
                    "started_at_ms", "finished_at_ms", "project", "batch_id", "worker",
                    "mission_name"});
  Job job;
  job.id = r.required<std::string>("id");
  job.mission_id = r.required<std::string>("mission_id");
  job.state = job_state_from_string(r.required<std::string>("state"), r.child("state"));
  job.stages = r.required<std::vector<std::string>>("stages");
  job.options = r.optional<nlohmann::json>("options", nlohmann::json::object());
  job.stage = r.optional<std::string>("stage", "");
  job.progress = r.optional<double>("progress", 0.0);
  job.completed_stages = r.optional<std::vector<std::string>>("completed_stages", {});
  if (r.has("stage_seconds")) {
    const auto& seconds = r.at("stage_seconds");
    if (!seconds.is_object())
      throw ContractError(r.child("stage_seconds") + ": expected object, got " +
                          json_type_name(seconds));
    for (const auto& item : seconds.items())
      job.stage_seconds[item.key()] =
          FieldReader::convert<double>(item.value(), r.child("stage_seconds") + "." + item.key());
  }
  job.error = r.optional<std::string>("error", "");
  job.attempts = r.optional<int>("attempts", 0);
  job.created_at_ms = r.optional<int64_t>("created_at_ms", 0);
  job.started_at_ms = r.optional<int64_t>("started_at_ms", 0);
  job.finished_at_ms = r.optional<int64_t>("finished_at_ms", 0);
  job.project = r.optional<std::string>("project", "");
  job.batch_id = r.optional<std::string>("batch_id", "");
  job.worker = r.optional<std::string>("worker", "");
  job.mission_name = r.optional<std::string>("mission_name", "");
  return job;
}

nlohmann::json ReprocessRequest::to_json() const {
  nlohmann::json out = {{"mission_ids", mission_ids},
                        {"name_prefix", name_prefix},
                        {"stages", stages},
                        {"options", options}};
  if (!project.empty()) out["project"] = project;
  if (compare) out["compare"] = true;
  return out;
}

ReprocessRequest ReprocessRequest::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"mission_ids", "name_prefix", "stages", "options", "project", "compare"});
  ReprocessRequest out;
  out.project = optional_project(r);
  out.mission_ids = r.optional<std::vector<std::string>>("mission_ids", {});
  out.name_prefix = r.optional<std::string>("name_prefix", "");
  out.stages = r.required<std::vector<std::string>>("stages");
  validate_stage_list(out.stages, r.child("stages"));
  out.options = r.optional<nlohmann::json>("options", nlohmann::json::object());
  validate_options(out.options, r.child("options"));
  out.compare = r.optional<bool>("compare", false);
  if (out.compare && std::find(out.stages.begin(), out.stages.end(), "compare") != out.stages.end())
    throw ContractError(r.child("stages") +
                        ": 'compare' is added by \"compare\": true; list the stages to run again");
  return out;
}

nlohmann::json Batch::to_json() const {
  nlohmann::json out = {{"id", id},
                        {"project", project},
                        {"created_at_ms", created_at_ms},
                        {"jobs", jobs},
                        {"jobs_by_state", state_counts(jobs_by_state)},
                        {"mean_job_seconds", mean_job_seconds},
                        {"finished_jobs_timed", finished_jobs_timed}};
  if (compared > 0) out["compared"] = compared;
  return out;
}

Batch Batch::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"id", "project", "created_at_ms", "jobs", "jobs_by_state", "mean_job_seconds",
                    "finished_jobs_timed", "compared"});
  Batch out;
  out.id = r.required<std::string>("id");
  out.project = r.optional<std::string>("project", "");
  out.created_at_ms = r.optional<int64_t>("created_at_ms", 0);
  out.jobs = r.required<int64_t>("jobs");
  if (r.has("jobs_by_state")) {
    const auto& counts = r.at("jobs_by_state");
    if (!counts.is_object())
      throw ContractError(r.child("jobs_by_state") + ": expected object, got " +
                          json_type_name(counts));
    for (const auto& item : counts.items()) {
      job_state_from_string(item.key(), r.child("jobs_by_state"));
      out.jobs_by_state[item.key()] =
          FieldReader::convert<int64_t>(item.value(), r.child("jobs_by_state") + "." + item.key());
    }
  }
  out.mean_job_seconds = r.optional<double>("mean_job_seconds", 0.0);
  out.finished_jobs_timed = r.optional<int64_t>("finished_jobs_timed", 0);
  out.compared = r.optional<int64_t>("compared", 0);
  return out;
}

nlohmann::json WorkerInfo::to_json() const {
  return {{"id", id}, {"job_id", job_id}, {"last_seen_ms", last_seen_ms}, {"alive", alive}};
}

nlohmann::json QueueSummary::to_json() const {
  nlohmann::json list = nlohmann::json::array();
  for (const WorkerInfo& worker : workers) list.push_back(worker.to_json());
  return {{"jobs_by_state", state_counts(jobs_by_state)},
          {"workers_alive", workers_alive},
          {"workers", list},
          {"finished_last_hour", finished_last_hour},
          {"failed_last_hour", failed_last_hour},
          {"mean_job_seconds_last_hour", mean_job_seconds_last_hour}};
}

nlohmann::json ComparisonRequest::to_json() const {
  return {{"job_a", job_a}, {"job_b", job_b}, {"options", options}};
}

ComparisonRequest ComparisonRequest::from_json(const nlohmann::json& body,
                                               const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"job_a", "job_b", "options"});
  ComparisonRequest out;
  out.job_a = r.required<std::string>("job_a");
  out.job_b = r.required<std::string>("job_b");
  if (out.job_a.empty()) throw ContractError(r.child("job_a") + ": expected a job id");
  if (out.job_b.empty()) throw ContractError(r.child("job_b") + ": expected a job id");
  if (r.has("options")) {
    out.options = r.at("options");
    if (!out.options.is_object())
      throw ContractError(r.child("options") + ": expected an object of compare stage options");
    for (const char* reserved : {"job_a", "job_b"})
      if (out.options.contains(reserved))
        throw ContractError(r.child("options") + "." + reserved + ": give it as " + reserved +
                            " of the request, not as an option");
  }
  return out;
}

}  // namespace keel::proto
