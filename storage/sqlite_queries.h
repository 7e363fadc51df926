// Reads shared by the SQLite store's methods: each finds one kind of row by id (or the
// rows of a job) and turns it into its proto type. They run on whatever connection the
// caller holds (the writer inside a transaction, or a pooled reader).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "proto/job.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"
#include "storage/sqlite_db.h"
#include "storage/store.h"

namespace keel::storage {

std::optional<proto::Upload> find_upload(Database& db, const std::string& upload_id);
std::optional<proto::Mission> find_mission(Database& db, const std::string& mission_id);
std::optional<proto::Job> find_job(Database& db, const std::string& job_id);
std::optional<proto::Artifact> find_artifact(Database& db, const std::string& artifact_id);
std::optional<int64_t> find_blob_size(Database& db, const std::string& sha256);

// The newest jobs first that pass `filter`.
std::vector<proto::Job> query_jobs(Database& db, const JobFilter& filter);
// The newest missions first whose name starts with `name_prefix`, of `project` ("" or "*" =
// every project).
std::vector<proto::Mission> query_missions(Database& db, const std::string& name_prefix,
                                           const std::string& project);
// A job's artifacts in the order they were registered.
std::vector<proto::Artifact> job_artifacts(Database& db, const std::string& job_id);
// The job's finished stages with their reports and artifacts, in the job's pipeline order.
std::vector<proto::StageOutput> completed_outputs(Database& db, const proto::Job& job);

// Index of `stage` in `stages`, or stages.size() when absent (sorts unknown stages last).
size_t pipeline_index(const std::vector<std::string>& stages, const std::string& stage);

}  // namespace keel::storage
