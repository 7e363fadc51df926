// What every Store implementation checks and says the same way (SQLite and PostgreSQL):
// limits, argument checks and the errors they throw, so the two stores cannot drift apart.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "proto/job.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"
#include "storage/store.h"

namespace keel::storage::rules {

// After this many expired leases a job fails instead of being leased again (docs/api.md).
inline constexpr int kMaxLeaseExpiries = 3;
inline constexpr size_t kMaxIdempotencyKeyBytes = 255;
inline constexpr size_t kMaxArtifactNameBytes = 255;
inline constexpr int kMaxListLimit = 10000;
// A worker that called the worker protocol this recently is alive (docs/api.md).
inline constexpr int64_t kWorkerAliveMs = 60'000;
inline constexpr int64_t kHourMs = 3'600'000;

NotFound job_not_found(const std::string& job_id);
NotFound upload_not_found(const std::string& upload_id);
NotFound mission_not_found(const std::string& mission_id);

// Invalid unless `sha256` is 64 lowercase hex digits; `field` names it in the message.
void require_sha256(const std::string& sha256, const std::string& field);
void require_project_name(const std::string& name, const std::string& field);
// Artifact names become download file names: one plain path component.
void require_artifact_name(const std::string& name);
// Invalid unless `stage` is one of the job's stages.
void require_stage_of(const proto::Job& job, const std::string& stage, const std::string& field);
// Invalid for an unknown stage or option (the contract's messages).
void require_pipeline(const std::vector<std::string>& stages, const nlohmann::json& options);
void require_idempotency_key(const std::string& key);
void require_upload_size(int64_t size);
void require_mission_request(const proto::MissionRequest& request);
void require_lease_seconds(int lease_seconds);
void require_progress(double progress);
void require_list_limit(int limit);
// The project a token spec may name ('*' only for admin and worker tokens).
void require_token_spec(const std::string& token, const TokenSpec& spec);

// A reprocess job that also compares with the job it reprocesses (ReprocessRequest::compare):
// its stages with `compare` last, and its options with options.compare.job_a = `earlier_job`.
struct BatchJobPipeline {
  std::string stages;   // JSON text, as the jobs table holds them
  std::string options;  // JSON text
};
BatchJobPipeline with_compare(const std::vector<std::string>& stages, nlohmann::json options,
                              const std::string& earlier_job);
// The jobs table's text of a comparison job's stages: such a job is never "the job a
// reprocess job reprocesses".
inline constexpr const char* kCompareOnlyStages = "[\"compare\"]";

// An Idempotency-Key reused with another request is a conflict.
bool same_request(const proto::Job& job, const proto::JobRequest& request);
// "" when succeeded, else the worker's message or a default.
std::string finish_error(const proto::JobFinish& finish, bool succeeded);

// The log line and error of an expired lease.
std::string expired_lease_line(const std::string& lease_id, const std::string& worker,
                               bool gave_up);
std::string expired_lease_error(int expiries, const std::string& worker);
std::string released_lease_line(const std::string& worker, const std::string& lease_id);
LeaseLost lease_lost(const std::string& job_id, const std::string& lease_id);

// Every job state with a count of 0.
std::map<std::string, int64_t> zero_counts();

}  // namespace keel::storage::rules
