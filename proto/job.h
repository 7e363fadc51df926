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
  std::string project;  // optional in JSON; the server checks it against the token's project

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
  std::string project;                        // the mission's project
  std::string batch_id;                       // the reprocess batch that made it, "" = none
  std::string worker;                         // holds (or last held) its lease, "" = none
  std::string mission_name;                   // the mission's name, for lists and filters

  nlohmann::json to_json() const;
  static Job from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/comparisons (issue 16): a `compare` job over two finished jobs of one project, A the
// earlier and B the later; `options` are the compare stage's ({"core_spacing_m": 0.05, ...}).
struct ComparisonRequest {
  std::string job_a, job_b;
  nlohmann::json options = nlohmann::json::object();

  nlohmann::json to_json() const;
  static ComparisonRequest from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/reprocess: a filter over stored missions and the pipeline to run on each.
struct ReprocessRequest {
  std::vector<std::string> mission_ids;  // explicit ids, or
  std::string name_prefix;               // missions whose name starts with this ("" = all)
  std::vector<std::string> stages;
  nlohmann::json options = nlohmann::json::object();
  std::string project;                   // optional in JSON; the server sets the token's
  // Each new job also compares its products with the job it reprocesses: the latest
  // succeeded job of its mission (a comparison job aside). Such a job runs `compare` after its
  // stages, with options.compare.job_a = that job (issue 16; docs/api.md "Reprocess").
  bool compare = false;

  nlohmann::json to_json() const;
  static ReprocessRequest from_json(const nlohmann::json& body, const std::string& path = "");
};

// The jobs one reprocess request made, followed as a whole (`keel jobs --batch ID`).
struct Batch {
  std::string id;  // "b_..."
  std::string project;
  int64_t created_at_ms = 0;
  int64_t jobs = 0;                              // jobs made
  int64_t compared = 0;  // of them, comparing with the job they reprocess (in create's answer)
  std::map<std::string, int64_t> jobs_by_state;  // every state, 0 included
  // Seconds of the batch's finished jobs (finished - started), for an ETA.
  double mean_job_seconds = 0.0;
  int64_t finished_jobs_timed = 0;

  nlohmann::json to_json() const;
  static Batch from_json(const nlohmann::json& body, const std::string& path = "");
};

// GET /v1/queue (docs/api.md "Live events and the queue").
struct WorkerInfo {
  std::string id;      // the worker's name from its lease requests (unique per process start)
  std::string job_id;  // the job it holds, "" when idle
  int64_t last_seen_ms = 0;
  bool alive = false;  // called the worker protocol within the last 60 s

  nlohmann::json to_json() const;
};
struct QueueSummary {
  std::map<std::string, int64_t> jobs_by_state;  // every state, 0 included
  int64_t workers_alive = 0;
  std::vector<WorkerInfo> workers;
  int64_t finished_last_hour = 0;  // succeeded or failed in the last hour
  int64_t failed_last_hour = 0;
  double mean_job_seconds_last_hour = 0.0;

  nlohmann::json to_json() const;
};

}  // namespace keel::proto
