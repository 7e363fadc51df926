// Reads shared by PgStore's methods, the PostgreSQL twins of sqlite_queries.h: each finds
// one kind of row by id (or the rows of a job) and turns it into its proto type, inside the
// caller's transaction.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "proto/job.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"
#include "storage/pg_connection.h"
#include "storage/store.h"

namespace keel::storage {

// The columns of a job (jobs aliased j, its mission m) and of a mission (m), for statements
// that return them beside others, and their decoders (`first`: index of the first column).
extern const char* const kPgJobColumns;
extern const char* const kPgMissionColumns;
inline constexpr int kPgJobColumnCount = 17;
proto::Job pg_read_job(const pqxx::row& row, int first);
proto::Mission pg_read_mission(const pqxx::row& row, int first);

std::optional<proto::Upload> pg_find_upload(PgTx& tx, const std::string& upload_id);
std::optional<proto::Mission> pg_find_mission(PgTx& tx, const std::string& mission_id);
std::optional<proto::Job> pg_find_job(PgTx& tx, const std::string& job_id);
std::optional<proto::Artifact> pg_find_artifact(PgTx& tx, const std::string& artifact_id);
std::optional<int64_t> pg_find_blob_size(PgTx& tx, const std::string& sha256);
// Notes that `project` references the blob (Store::project_usage, project_has_blob).
void pg_note_blob_ref(PgTx& tx, const std::string& project, const std::string& sha256);

// The newest jobs first that pass `filter`.
std::vector<proto::Job> pg_query_jobs(PgTx& tx, const JobFilter& filter);
// The newest missions first whose name starts with `name_prefix`, of `project` ("" or "*" =
// every project).
std::vector<proto::Mission> pg_query_missions(PgTx& tx, const std::string& name_prefix,
                                              const std::string& project);
// A job's artifacts in the order they were registered.
std::vector<proto::Artifact> pg_job_artifacts(PgTx& tx, const std::string& job_id);
// The job's finished stages with their reports and artifacts, in the job's pipeline order.
std::vector<proto::StageOutput> pg_completed_outputs(PgTx& tx, const proto::Job& job);

// A PostgreSQL text[] literal of `values` ('{"a","b"}'), every element quoted and escaped.
std::string pg_text_array(const std::vector<std::string>& values);

}  // namespace keel::storage
