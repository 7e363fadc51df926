// Jobs: a mission, its stages with options, and a state
// queued -> running(stage, progress) -> succeeded | failed(error) | canceled.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace keel::proto {

enum class JobState { kQueued, kRunning, kSucceeded, kFailed, kCanceled };

std::string to_string(JobState state);
// Fails with a ContractError naming `path` for an unknown state.
JobState job_state_from_string(std::string_view text, const std::string& path = "state");
bool is_terminal(JobState state);

// What a client sends to create a job (POST /v1/jobs).
struct JobRequest {
  std::string mission_id;
  std::vector<std::string> stages;
  nlohmann::json options = nlohmann::json::object();  // {"stage": {"option": value}}

  nlohmann::json to_json() const;
  static JobRequest from_json(const nlohmann::json& body, const std::string& path = "");
};

struct Job {
  std::string id;
  std::string mission_id;
  JobState state = JobState::kQueued;
  std::vector<std::string> stages;
  nlohmann::json options = nlohmann::json::object();
  std::string stage;                          // running stage ("" when none)
  double progress = 0.0;                      // of the running stage, 0..1
  std::vector<std::string> completed_stages;  // kept across retries
  std::map<std::string, double> stage_seconds;
  std::string error;                          // set when failed
  int attempts = 0;                           // leases taken so far
  int64_t created_at_ms = 0;
  int64_t started_at_ms = 0;                  // 0 = not yet
  int64_t finished_at_ms = 0;                 // 0 = not yet

  nlohmann::json to_json() const;
  static Job from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/reprocess: a filter over stored missions and the pipeline to run on each.
struct ReprocessRequest {
  std::vector<std::string> mission_ids;  // explicit ids, or
  std::string name_prefix;               // missions whose name starts with this ("" = all)
  std::vector<std::string> stages;
  nlohmann::json options = nlohmann::json::object();

  nlohmann::json to_json() const;
  static ReprocessRequest from_json(const nlohmann::json& body, const std::string& path = "");
};

}  // namespace keel::proto
