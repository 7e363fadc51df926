#include "storage/sql_queries.h"

#include <algorithm>

#include "proto/contract_error.h"
#include "proto/options.h"

namespace keel::storage {

namespace {

// --- column lists and their decoders (keep each pair in step) ---

const std::string kUploadSelect = "SELECT id, name, size, committed, project FROM uploads";

proto::Upload read_upload(const SqlRow& row) {
  return {row.text(0), row.text(1), row.int64(2), row.int64(3), "", row.text(4)};
}

const std::string kMissionSelect =
    "SELECT m.id, m.name, m.bundle_blob, COALESCE(m.cad_blob, ''), m.cad_name, m.created_at_ms, "
    "m.project FROM missions m";

proto::Mission read_mission(const SqlRow& row) {
  return {row.text(0), row.text(1),  row.text(2), row.text(3),
          row.text(4), row.int64(5), row.text(6)};
}

// One statement reads the job and its finished stages, so both come from one snapshot.
const std::string kJobSelect =
    "SELECT j.id, j.mission_id, j.state, j.stages, j.options, j.stage, j.progress, j.error, "
    "j.attempts, j.created_at_ms, j.started_at_ms, j.finished_at_ms, {stage_seconds}, "
    "j.project, j.batch_id, j.worker, m.name FROM jobs j JOIN missions m ON m.id = j.mission_id";

proto::Job read_job(const SqlRow& row) {
  proto::Job job;
  job.id = row.text(0);
  job.mission_id = row.text(1);
  job.state = proto::job_state_from_string(row.text(2), "jobs.state of " + job.id);
  job.stages = nlohmann::json::parse(row.text(3)).get<std::vector<std::string>>();
  job.options = nlohmann::json::parse(row.text(4));
  job.stage = row.text(5);
  job.progress = row.real(6);
  job.error = row.text(7);
  job.attempts = static_cast<int>(row.int64(8));
  job.created_at_ms = row.int64(9);
  job.started_at_ms = row.int64(10);
  job.finished_at_ms = row.int64(11);
  for (const auto& done : nlohmann::json::parse(row.text(12))) {
    job.completed_stages.push_back(done[0].get<std::string>());
    job.stage_seconds[done[0].get<std::string>()] = done[1].get<double>();
  }
  job.project = row.text(13);
  job.batch_id = row.text(14);
  job.worker = row.text(15);
  job.mission_name = row.text(16);
  std::stable_sort(job.completed_stages.begin(), job.completed_stages.end(),
                   [&](const std::string& a, const std::string& b) {
                     return pipeline_index(job.stages, a) < pipeline_index(job.stages, b);
                   });
  return job;
}

const std::string kArtifactSelect =
    "SELECT a.id, a.job_id, a.stage, a.name, a.sha256, a.size, a.created_at_ms, j.project "
    "FROM artifacts a JOIN jobs j ON j.id = a.job_id";

proto::Artifact read_artifact(const SqlRow& row) {
  return {row.text(0), row.text(1),  row.text(2),  row.text(3),
          row.text(4), row.int64(5), row.int64(6), row.text(7)};
}

template <typename Read>
auto find_one(SqlTx& tx, const std::string& sql, const std::string& key, Read read)
    -> std::optional<decltype(read(std::declval<const SqlRow&>()))> {
  auto row = tx.row(sql, {key});
  if (!row) return std::nullopt;
  return read(*row);
}

// "" and "*" mean every project: the statements read "" as "any".
std::string project_filter(const std::string& project) {
  return project == proto::kAllProjects ? std::string() : project;
}

}  // namespace

NotFound job_not_found(const std::string& job_id) {
  return NotFound("job " + job_id + " not found");
}

void require_sha256(const std::string& sha256, const std::string& field) {
  if (!proto::is_sha256_hex(sha256))
    throw Invalid(field + ": expected 64 lowercase hex digits (SHA-256), got '" + sha256 + "'");
}

void require_pipeline(const std::vector<std::string>& stages, const nlohmann::json& options) {
  try {
    proto::validate_stage_list(stages, "stages");
    proto::validate_options(options, "options");
  } catch (const proto::ContractError& error) {
    throw Invalid(error.what());
  }
}

size_t pipeline_index(const std::vector<std::string>& stages, const std::string& stage) {
  return static_cast<size_t>(std::find(stages.begin(), stages.end(), stage) - stages.begin());
}

std::optional<proto::Upload> find_upload(SqlTx& tx, const std::string& upload_id, bool lock) {
  return find_one(tx, kUploadSelect + " WHERE id = ?1" + (lock ? "{for_update}" : ""), upload_id,
                  read_upload);
}

std::optional<proto::Mission> find_mission(SqlTx& tx, const std::string& mission_id) {
  return find_one(tx, kMissionSelect + " WHERE m.id = ?1", mission_id, read_mission);
}

std::optional<proto::Job> find_job(SqlTx& tx, const std::string& job_id) {
  return find_one(tx, kJobSelect + " WHERE j.id = ?1", job_id, read_job);
}

proto::Job require_job(SqlTx& tx, const std::string& job_id) {
  auto job = find_job(tx, job_id);
  if (!job) throw job_not_found(job_id);
  return *job;
}

std::optional<proto::Artifact> find_artifact(SqlTx& tx, const std::string& artifact_id) {
  return find_one(tx, kArtifactSelect + " WHERE a.id = ?1", artifact_id, read_artifact);
}

std::optional<int64_t> find_blob_size(SqlTx& tx, const std::string& sha256) {
  return find_one(tx, "SELECT size FROM blobs WHERE sha256 = ?1", sha256,
                  [](const SqlRow& row) { return row.int64(0); });
}

std::vector<proto::Job> query_jobs(SqlTx& tx, const JobFilter& filter) {
  // '' means "any".
  return read_rows(
      tx,
      kJobSelect +
          " WHERE (?1 = '' OR j.state = ?1) AND (?2 = '' OR j.mission_id = ?2) "
          "AND (?4 = '' OR j.project = ?4) AND (?5 = '' OR j.batch_id = ?5) "
          "AND (?6 = '' OR {instr}(m.name, ?6) > 0) ORDER BY j.seq DESC LIMIT ?3",
      {filter.state ? proto::to_string(*filter.state) : std::string(), filter.mission_id,
       int64_t{filter.limit}, project_filter(filter.project), filter.batch_id, filter.mission_name},
      read_job);
}

std::vector<proto::Mission> query_missions(SqlTx& tx, const std::string& name_prefix,
                                           const std::string& project) {
  return read_rows(tx,
                   kMissionSelect +
                       " WHERE (?1 = '' OR {instr}(m.name, ?1) = 1) "
                       "AND (?2 = '' OR m.project = ?2) ORDER BY m.seq DESC",
                   {name_prefix, project_filter(project)}, read_mission);
}

std::vector<proto::Artifact> job_artifacts(SqlTx& tx, const std::string& job_id) {
  return read_rows(tx, kArtifactSelect + " WHERE a.job_id = ?1 ORDER BY a.seq", {job_id},
                   read_artifact);
}

std::vector<proto::StageOutput> completed_outputs(SqlTx& tx, const proto::Job& job) {
  std::vector<proto::StageOutput> outputs =
      read_rows(tx, "SELECT stage, report, seconds FROM stage_outputs WHERE job_id = ?1", {job.id},
                [](const SqlRow& row) {
                  proto::StageOutput output;
                  output.stage = row.text(0);
                  output.report = nlohmann::json::parse(row.text(1));
                  output.seconds = row.real(2);
                  return output;
                });
  if (!outputs.empty())
    for (proto::Artifact& artifact : job_artifacts(tx, job.id))
      for (proto::StageOutput& output : outputs)
        if (output.stage == artifact.stage) {
          output.artifacts.push_back(std::move(artifact));
          break;
        }
  std::stable_sort(outputs.begin(), outputs.end(),
                   [&](const proto::StageOutput& a, const proto::StageOutput& b) {
                     return pipeline_index(job.stages, a.stage) <
                            pipeline_index(job.stages, b.stage);
                   });
  return outputs;
}

}  // namespace keel::storage
