// What SqlStore's files share: reads that find one kind of row by id (or the rows of a job)
// and turn it into its proto type, inside the caller's transaction, and the checks and errors
// more than one of them says the same way.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "proto/job.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"
#include "storage/sql.h"
#include "storage/store.h"

namespace keel::storage {

// `lock`: hold the row until the commit ({for_update}).
// Each row `sql` returns, turned into its type by `read`.
template <typename Read>
auto read_rows(SqlTx& tx, const std::string& sql, const std::vector<SqlValue>& params, Read read) {
  std::vector<decltype(read(std::declval<const SqlRow&>()))> out;
  for (const SqlRow& row : tx.query(sql, params)) out.push_back(read(row));
  return out;
}

std::optional<proto::Upload> find_upload(SqlTx& tx, const std::string& upload_id,
                                         bool lock = false);
std::optional<proto::Mission> find_mission(SqlTx& tx, const std::string& mission_id);
std::optional<proto::Job> find_job(SqlTx& tx, const std::string& job_id);
std::optional<proto::Artifact> find_artifact(SqlTx& tx, const std::string& artifact_id);
std::optional<int64_t> find_blob_size(SqlTx& tx, const std::string& sha256);
// NotFound unless the job exists.
proto::Job require_job(SqlTx& tx, const std::string& job_id);

// The newest jobs first that pass `filter`.
std::vector<proto::Job> query_jobs(SqlTx& tx, const JobFilter& filter);
// The newest missions first whose name starts with `name_prefix`, of `project` ("" or "*" =
// every project).
std::vector<proto::Mission> query_missions(SqlTx& tx, const std::string& name_prefix,
                                           const std::string& project);
// A job's artifacts in the order they were registered.
std::vector<proto::Artifact> job_artifacts(SqlTx& tx, const std::string& job_id);
// The job's finished stages with their reports and artifacts, in the job's pipeline order.
std::vector<proto::StageOutput> completed_outputs(SqlTx& tx, const proto::Job& job);

// Notes that `project` references the blob (Store::project_usage, project_has_blob).
void note_blob_ref(SqlTx& tx, const std::string& project, const std::string& sha256);

NotFound job_not_found(const std::string& job_id);
// Invalid unless `sha256` is 64 lowercase hex digits; `field` names it in the message.
void require_sha256(const std::string& sha256, const std::string& field);
// Invalid for an unknown stage or option (the contract's messages).
void require_pipeline(const std::vector<std::string>& stages, const nlohmann::json& options);

// Index of `stage` in `stages`, or stages.size() when absent (sorts unknown stages last).
size_t pipeline_index(const std::vector<std::string>& stages, const std::string& stage);

}  // namespace keel::storage
