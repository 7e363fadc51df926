// The worker side of the API: lease, heartbeat, stage completion, artifacts, complete/fail.
// Workers use HTTP like clients and never touch the database, so they can run anywhere.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "proto/job.h"
#include "proto/resources.h"

namespace keel::proto {

// POST /v1/worker/lease
struct LeaseRequest {
  LeaseRequest() = default;
  LeaseRequest(std::string worker_name, int seconds)
      : worker(std::move(worker_name)), lease_seconds(seconds) {}

  std::string worker;       // a name for logs and /metrics ("host:pid:start"), unique per process
  int lease_seconds = 30;   // the lease expires unless a heartbeat extends it
  // Long poll: when nothing is queued, wait up to this long for a job (0..30 s) before the
  // 204 answer. The server wakes the waiter as soon as a job is queued on any replica.
  int wait_seconds = 0;
  // Not in JSON: set by the server from the worker's token (kAllProjects = any project).
  std::string project;

  nlohmann::json to_json() const;
  static LeaseRequest from_json(const nlohmann::json& body, const std::string& path = "");
};

// A finished stage of a job, kept so a retry resumes after it.
struct StageOutput {
  std::string stage;
  nlohmann::json report = nlohmann::json::object();  // the stage's section of report.json
  std::vector<Artifact> artifacts;
  double seconds = 0.0;

  nlohmann::json to_json() const;
  static StageOutput from_json(const nlohmann::json& body, const std::string& path = "");
};

// A finished job that a `compare` job reads (issue 16): its record and its artifacts.
struct LeaseInput {
  Job job;
  std::vector<Artifact> artifacts;

  nlohmann::json to_json() const;
  static LeaseInput from_json(const nlohmann::json& body, const std::string& path = "");
};

// 200 answer to a lease (204 when no job is queued).
struct Lease {
  std::string lease_id;
  int64_t expires_at_ms = 0;
  Job job;
  Mission mission;
  std::vector<StageOutput> completed;  // stages finished by earlier attempts, in order
  std::vector<LeaseInput> inputs;      // a compare job's jobs A then B (the store fills them)

  nlohmann::json to_json() const;
  static Lease from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/worker/jobs/{id}/heartbeat
struct Heartbeat {
  std::string lease_id;
  std::string stage;
  double progress = 0.0;
  std::vector<std::string> log;  // new log lines since the last heartbeat

  nlohmann::json to_json() const;
  static Heartbeat from_json(const nlohmann::json& body, const std::string& path = "");
};

struct HeartbeatReply {
  bool canceled = false;  // the job was canceled: stop within 2 s, report nothing more
  int64_t expires_at_ms = 0;

  nlohmann::json to_json() const;
  static HeartbeatReply from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/worker/jobs/{id}/artifacts: registers an uploaded blob as an artifact.
struct ArtifactRegistration {
  std::string lease_id;
  std::string stage;
  std::string name;
  std::string blob;

  nlohmann::json to_json() const;
  static ArtifactRegistration from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/worker/jobs/{id}/stages/{stage}/complete
struct StageCompletion {
  std::string lease_id;
  nlohmann::json report = nlohmann::json::object();
  double seconds = 0.0;

  nlohmann::json to_json() const;
  static StageCompletion from_json(const nlohmann::json& body, const std::string& path = "");
};

// POST /v1/worker/jobs/{id}/complete and /fail (error set only for fail).
struct JobFinish {
  std::string lease_id;
  std::string error;

  nlohmann::json to_json() const;
  static JobFinish from_json(const nlohmann::json& body, const std::string& path = "");
};

// GET /v1/jobs/{id}/log?from=N answer.
struct LogLine {
  int64_t seq = 0;
  int64_t t_ms = 0;
  std::string text;
};
struct LogPage {
  std::vector<LogLine> lines;
  int64_t next = 0;  // pass as ?from= to get the lines after these

  nlohmann::json to_json() const;
  static LogPage from_json(const nlohmann::json& body, const std::string& path = "");
};

}  // namespace keel::proto
