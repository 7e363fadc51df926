#include "storage/sqlite_queries.h"

#include <algorithm>

namespace keel::storage {

namespace {

// --- column lists and their decoders (keep each pair in step) ---

constexpr const char* kUploadSelect = "SELECT id, name, size, committed, project FROM uploads";

proto::Upload read_upload(const Statement& row) {
  proto::Upload upload;
  upload.id = row.column_text(0);
  upload.name = row.column_text(1);
  upload.size = row.column_int64(2);
  upload.offset = row.column_int64(3);
  upload.project = row.column_text(4);
  return upload;
}

constexpr const char* kMissionSelect =
    "SELECT id, name, bundle_blob, cad_blob, cad_name, created_at_ms, project FROM missions";

proto::Mission read_mission(const Statement& row) {
  proto::Mission mission;
  mission.id = row.column_text(0);
  mission.name = row.column_text(1);
  mission.bundle_blob = row.column_text(2);
  mission.cad_blob = row.column_text(3);
  mission.cad_name = row.column_text(4);
  mission.created_at_ms = row.column_int64(5);
  mission.project = row.column_text(6);
  return mission;
}

// One statement reads the job and its finished stages, so both come from one snapshot.
constexpr const char* kJobSelect =
    "SELECT j.id, j.mission_id, j.state, j.stages, j.options, j.stage, j.progress, j.error, "
    "j.attempts, j.created_at_ms, j.started_at_ms, j.finished_at_ms, "
    "(SELECT json_group_array(json_array(o.stage, o.seconds)) FROM stage_outputs o "
    "WHERE o.job_id = j.id), j.project, j.batch_id, j.worker, m.name "
    "FROM jobs j JOIN missions m ON m.id = j.mission_id";

proto::Job read_job(const Statement& row) {
  proto::Job job;
  job.id = row.column_text(0);
  job.mission_id = row.column_text(1);
  job.state = proto::job_state_from_string(row.column_text(2), "jobs.state of " + job.id);
  job.stages = nlohmann::json::parse(row.column_text(3)).get<std::vector<std::string>>();
  job.options = nlohmann::json::parse(row.column_text(4));
  job.stage = row.column_text(5);
  job.progress = row.column_double(6);
  job.error = row.column_text(7);
  job.attempts = static_cast<int>(row.column_int64(8));
  job.created_at_ms = row.column_int64(9);
  job.started_at_ms = row.column_int64(10);
  job.finished_at_ms = row.column_int64(11);
  for (const auto& done : nlohmann::json::parse(row.column_text(12))) {
    job.completed_stages.push_back(done[0].get<std::string>());
    job.stage_seconds[done[0].get<std::string>()] = done[1].get<double>();
  }
  job.project = row.column_text(13);
  job.batch_id = row.column_text(14);
  job.worker = row.column_text(15);
  job.mission_name = row.column_text(16);
  std::stable_sort(job.completed_stages.begin(), job.completed_stages.end(),
                   [&](const std::string& a, const std::string& b) {
                     return pipeline_index(job.stages, a) < pipeline_index(job.stages, b);
                   });
  return job;
}

constexpr const char* kArtifactSelect =
    "SELECT a.id, a.job_id, a.stage, a.name, a.sha256, a.size, a.created_at_ms, j.project "
    "FROM artifacts a JOIN jobs j ON j.id = a.job_id";

proto::Artifact read_artifact(const Statement& row) {
  proto::Artifact artifact;
  artifact.id = row.column_text(0);
  artifact.job_id = row.column_text(1);
  artifact.stage = row.column_text(2);
  artifact.name = row.column_text(3);
  artifact.sha256 = row.column_text(4);
  artifact.size = row.column_int64(5);
  artifact.created_at_ms = row.column_int64(6);
  artifact.project = row.column_text(7);
  return artifact;
}

template <typename T, typename Read>
std::optional<T> find_one(Database& db, const std::string& sql, const std::string& key, Read read) {
  auto statement = db.cached(sql);
  statement->bind_text(1, key);
  if (!statement->step()) return std::nullopt;
  return read(*statement);
}

}  // namespace

size_t pipeline_index(const std::vector<std::string>& stages, const std::string& stage) {
  return static_cast<size_t>(std::find(stages.begin(), stages.end(), stage) - stages.begin());
}

std::optional<proto::Upload> find_upload(Database& db, const std::string& upload_id) {
  static const std::string sql = std::string(kUploadSelect) + " WHERE id = ?1";
  return find_one<proto::Upload>(db, sql, upload_id, read_upload);
}

std::optional<proto::Mission> find_mission(Database& db, const std::string& mission_id) {
  static const std::string sql = std::string(kMissionSelect) + " WHERE id = ?1";
  return find_one<proto::Mission>(db, sql, mission_id, read_mission);
}

std::optional<proto::Job> find_job(Database& db, const std::string& job_id) {
  static const std::string sql = std::string(kJobSelect) + " WHERE j.id = ?1";
  return find_one<proto::Job>(db, sql, job_id, read_job);
}

std::optional<proto::Artifact> find_artifact(Database& db, const std::string& artifact_id) {
  static const std::string sql = std::string(kArtifactSelect) + " WHERE a.id = ?1";
  return find_one<proto::Artifact>(db, sql, artifact_id, read_artifact);
}

std::optional<int64_t> find_blob_size(Database& db, const std::string& sha256) {
  auto statement = db.cached("SELECT size FROM blobs WHERE sha256 = ?1");
  statement->bind_text(1, sha256);
  if (!statement->step()) return std::nullopt;
  return statement->column_int64(0);
}

std::vector<proto::Job> query_jobs(Database& db, const JobFilter& filter) {
  // NULL parameters mean "any"; the planner still uses one of the jobs_by_* indexes.
  static const std::string sql =
      std::string(kJobSelect) +
      " WHERE (?1 IS NULL OR j.state = ?1) AND (?2 IS NULL OR j.mission_id = ?2) "
      "AND (?4 IS NULL OR j.project = ?4) AND (?5 IS NULL OR j.batch_id = ?5) "
      "AND (?6 IS NULL OR instr(m.name, ?6) > 0) "
      "ORDER BY j.seq DESC LIMIT ?3";
  auto statement = db.cached(sql);
  if (filter.state)
    statement->bind_text(1, proto::to_string(*filter.state));
  else
    statement->bind_null(1);
  const bool any_project = filter.project.empty() || filter.project == proto::kAllProjects;
  statement->bind_text_or_null(2, filter.mission_id)
      .bind_int64(3, filter.limit)
      .bind_text_or_null(4, any_project ? std::string() : filter.project)
      .bind_text_or_null(5, filter.batch_id)
      .bind_text_or_null(6, filter.mission_name);
  std::vector<proto::Job> jobs;
  while (statement->step()) jobs.push_back(read_job(*statement));
  return jobs;
}

std::vector<proto::Mission> query_missions(Database& db, const std::string& name_prefix,
                                           const std::string& project) {
  static const std::string sql = std::string(kMissionSelect) +
                                 " WHERE (?1 = '' OR instr(name, ?1) = 1) "
                                 "AND (?2 IS NULL OR project = ?2) ORDER BY seq DESC";
  auto statement = db.cached(sql);
  const bool any_project = project.empty() || project == proto::kAllProjects;
  statement->bind_text(1, name_prefix).bind_text_or_null(2, any_project ? std::string() : project);
  std::vector<proto::Mission> missions;
  while (statement->step()) missions.push_back(read_mission(*statement));
  return missions;
}

std::vector<proto::Artifact> job_artifacts(Database& db, const std::string& job_id) {
  static const std::string sql =
      std::string(kArtifactSelect) + " WHERE a.job_id = ?1 ORDER BY a.seq";
  auto statement = db.cached(sql);
  statement->bind_text(1, job_id);
  std::vector<proto::Artifact> artifacts;
  while (statement->step()) artifacts.push_back(read_artifact(*statement));
  return artifacts;
}

std::vector<proto::StageOutput> completed_outputs(Database& db, const proto::Job& job) {
  std::vector<proto::StageOutput> outputs;
  {
    auto statement =
        db.cached("SELECT stage, report, seconds FROM stage_outputs WHERE job_id = ?1");
    statement->bind_text(1, job.id);
    while (statement->step()) {
      proto::StageOutput output;
      output.stage = statement->column_text(0);
      output.report = nlohmann::json::parse(statement->column_text(1));
      output.seconds = statement->column_double(2);
      outputs.push_back(std::move(output));
    }
  }
  for (proto::Artifact& artifact : job_artifacts(db, job.id))
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
