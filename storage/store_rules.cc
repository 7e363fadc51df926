#include "storage/store_rules.h"

#include <cmath>

#include "proto/auth.h"
#include "proto/contract_error.h"
#include "proto/options.h"
#include "storage/sql_queries.h"  // pipeline_index

namespace keel::storage::rules {

NotFound job_not_found(const std::string& job_id) {
  return NotFound("job " + job_id + " not found");
}

NotFound upload_not_found(const std::string& upload_id) {
  return NotFound("upload " + upload_id + " not found");
}

NotFound mission_not_found(const std::string& mission_id) {
  return NotFound("mission " + mission_id + " not found");
}

void require_sha256(const std::string& sha256, const std::string& field) {
  if (!proto::is_sha256_hex(sha256))
    throw Invalid(field + ": expected 64 lowercase hex digits (SHA-256), got '" + sha256 + "'");
}

void require_project_name(const std::string& name, const std::string& field) {
  if (!proto::is_project_name(name))
    throw Invalid(field + ": project name '" + name +
                  "' must be 1..64 characters of a-z, 0-9, '.', '_' or '-', starting with a "
                  "letter or digit");
}

void require_artifact_name(const std::string& name) {
  if (name.empty() || name.size() > kMaxArtifactNameBytes || name == "." || name == "..")
    throw Invalid("name: expected a file name of 1.." + std::to_string(kMaxArtifactNameBytes) +
                  " bytes, got '" + name + "'");
  for (char c : name)
    if (c == '/' || c == '\\' || static_cast<unsigned char>(c) < 0x20)
      throw Invalid("name: artifact name '" + name +
                    "' must not contain '/', '\\' or control characters");
}

void require_stage_of(const proto::Job& job, const std::string& stage, const std::string& field) {
  if (pipeline_index(job.stages, stage) == job.stages.size())
    throw Invalid(field + ": job " + job.id + " has no stage '" + stage +
                  "' (its stages: " + nlohmann::json(job.stages).dump() + ")");
}

void require_pipeline(const std::vector<std::string>& stages, const nlohmann::json& options) {
  try {
    proto::validate_stage_list(stages, "stages");
    proto::validate_options(options, "options");
  } catch (const proto::ContractError& error) {
    throw Invalid(error.what());
  }
}

BatchJobPipeline with_compare(const std::vector<std::string>& stages, nlohmann::json options,
                              const std::string& earlier_job) {
  std::vector<std::string> with = stages;
  with.push_back("compare");
  if (!options.is_object()) options = nlohmann::json::object();
  if (!options.contains("compare") || !options["compare"].is_object())
    options["compare"] = nlohmann::json::object();
  options["compare"]["job_a"] = earlier_job;  // job_b: the job itself (compare_stage.h)
  return {nlohmann::json(with).dump(), options.dump()};
}

void require_idempotency_key(const std::string& key) {
  if (key.size() > kMaxIdempotencyKeyBytes)
    throw Invalid("Idempotency-Key: expected at most " + std::to_string(kMaxIdempotencyKeyBytes) +
                  " bytes");
}

void require_upload_size(int64_t size) {
  if (size < 0) throw Invalid("upload size: expected >= 0 bytes, got " + std::to_string(size));
}

void require_mission_request(const proto::MissionRequest& request) {
  if (request.name.empty()) throw Invalid("name: expected a non-empty mission name");
  require_sha256(request.bundle_blob, "bundle_blob");
  if (!request.cad_blob.empty()) {
    require_sha256(request.cad_blob, "cad_blob");
    if (request.cad_name.empty())
      throw Invalid("cad_name: required with cad_blob (its extension tells the mesh format)");
  } else if (!request.cad_name.empty()) {
    throw Invalid("cad_name: given without cad_blob");
  }
}

void require_lease_seconds(int lease_seconds) {
  if (lease_seconds < 1)
    throw Invalid("lease_seconds: expected >= 1, got " + std::to_string(lease_seconds));
}

void require_progress(double progress) {
  if (!(progress >= 0.0 && progress <= 1.0))
    throw Invalid("progress: expected a fraction in [0, 1]");
}

void require_list_limit(int limit) {
  if (limit < 1 || limit > kMaxListLimit)
    throw Invalid("limit: expected 1.." + std::to_string(kMaxListLimit) + ", got " +
                  std::to_string(limit));
}

void require_token_spec(const std::string& token, const TokenSpec& spec) {
  if (token.empty()) throw Invalid("token: expected a non-empty token");
  if (spec.project == proto::kAllProjects) {
    if (spec.role != proto::Role::kAdmin && spec.role != proto::Role::kWorker)
      throw Invalid("project: '*' (every project) is only for admin and worker tokens");
  } else {
    require_project_name(spec.project, "project");
  }
}

bool same_request(const proto::Job& job, const proto::JobRequest& request) {
  return job.mission_id == request.mission_id && job.stages == request.stages &&
         job.options == request.options;
}

std::string finish_error(const proto::JobFinish& finish, bool succeeded) {
  if (succeeded) return "";
  return finish.error.empty() ? "the worker failed without a message" : finish.error;
}

std::string expired_lease_line(const std::string& lease_id, const std::string& worker,
                               bool gave_up) {
  return "lease " + lease_id + " of worker " + worker + " expired" +
         (gave_up ? "; the job failed" : "; the job is queued again");
}

std::string expired_lease_error(int expiries, const std::string& worker) {
  return "lease expired " + std::to_string(expiries) + " times (last worker: " + worker + ")";
}

std::string released_lease_line(const std::string& worker, const std::string& lease_id) {
  return "worker " + worker + " gave lease " + lease_id + " back; the job is queued again";
}

LeaseLost lease_lost(const std::string& job_id, const std::string& lease_id) {
  return LeaseLost("job " + job_id + ": lease " + lease_id +
                   " is not the job's current lease (it expired and the job was queued "
                   "again, or the job finished or was retried)");
}

std::map<std::string, int64_t> zero_counts() {
  std::map<std::string, int64_t> counts;
  for (auto state :
       {proto::JobState::kQueued, proto::JobState::kRunning, proto::JobState::kSucceeded,
        proto::JobState::kFailed, proto::JobState::kCanceled})
    counts[proto::to_string(state)] = 0;
  return counts;
}

}  // namespace keel::storage::rules
