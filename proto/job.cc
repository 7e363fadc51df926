#include "proto/job.h"

#include "proto/contract_error.h"
#include "proto/options.h"

namespace keel::proto {

namespace {
constexpr std::pair<JobState, const char*> kStateNames[] = {
    {JobState::kQueued, "queued"},       {JobState::kRunning, "running"},
    {JobState::kSucceeded, "succeeded"}, {JobState::kFailed, "failed"},
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
  return state == JobState::kSucceeded || state == JobState::kFailed || state == JobState::kCanceled;
}

nlohmann::json JobRequest::to_json() const {
  return {{"mission_id", mission_id}, {"stages", stages}, {"options", options}};
}

JobRequest JobRequest::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"mission_id", "stages", "options"});
  JobRequest out;
  out.mission_id = r.required<std::string>("mission_id");
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
          {"finished_at_ms", finished_at_ms}};
}

Job Job::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"id", "mission_id", "state", "stages", "options", "stage", "progress",
                    "completed_stages", "stage_seconds", "error", "attempts", "created_at_ms",
                    "started_at_ms", "finished_at_ms"});
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
      throw ContractError(r.child("stage_seconds") + ": expected object, got " + json_type_name(seconds));
    for (const auto& item : seconds.items())
      job.stage_seconds[item.key()] = FieldReader::convert<double>(
          item.value(), r.child("stage_seconds") + "." + item.key());
  }
  job.error = r.optional<std::string>("error", "");
  job.attempts = r.optional<int>("attempts", 0);
  job.created_at_ms = r.optional<int64_t>("created_at_ms", 0);
  job.started_at_ms = r.optional<int64_t>("started_at_ms", 0);
  job.finished_at_ms = r.optional<int64_t>("finished_at_ms", 0);
  return job;
}

nlohmann::json ReprocessRequest::to_json() const {
  return {{"mission_ids", mission_ids}, {"name_prefix", name_prefix}, {"stages", stages},
          {"options", options}};
}

ReprocessRequest ReprocessRequest::from_json(const nlohmann::json& body, const std::string& path) {
  FieldReader r(body, path);
  r.reject_unknown({"mission_ids", "name_prefix", "stages", "options"});
  ReprocessRequest out;
  out.mission_ids = r.optional<std::vector<std::string>>("mission_ids", {});
  out.name_prefix = r.optional<std::string>("name_prefix", "");
  out.stages = r.required<std::vector<std::string>>("stages");
  validate_stage_list(out.stages, r.child("stages"));
  out.options = r.optional<nlohmann::json>("options", nlohmann::json::object());
  validate_options(out.options, r.child("options"));
  return out;
}

}  // namespace keel::proto
