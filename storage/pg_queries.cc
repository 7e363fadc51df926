#include "storage/pg_queries.h"

#include <algorithm>

#include "storage/sqlite_queries.h"  // pipeline_index

namespace keel::storage {

namespace {

// --- column lists and their decoders (keep each pair in step) ---

constexpr const char* kUploadSelect = "SELECT id, name, size, committed, project FROM uploads";

proto::Upload read_upload(const pqxx::row& row) {
  proto::Upload upload;
  upload.id = row[0].as<std::string>();
  upload.name = row[1].as<std::string>();
  upload.size = row[2].as<int64_t>();
  upload.offset = row[3].as<int64_t>();
  upload.project = row[4].as<std::string>();
  return upload;
}

constexpr const char* kMissionSelect =
    "SELECT m.id, m.name, m.bundle_blob, COALESCE(m.cad_blob, ''), m.cad_name, m.created_at_ms, "
    "m.project FROM missions m";

constexpr const char* kArtifactSelect =
    "SELECT a.id, a.job_id, a.stage, a.name, a.sha256, a.size, a.created_at_ms, j.project "
    "FROM artifacts a JOIN jobs j ON j.id = a.job_id";

proto::Artifact read_artifact(const pqxx::row& row) {
  proto::Artifact artifact;
  artifact.id = row[0].as<std::string>();
  artifact.job_id = row[1].as<std::string>();
  artifact.stage = row[2].as<std::string>();
  artifact.name = row[3].as<std::string>();
  artifact.sha256 = row[4].as<std::string>();
  artifact.size = row[5].as<int64_t>();
  artifact.created_at_ms = row[6].as<int64_t>();
  artifact.project = row[7].as<std::string>();
  return artifact;
}

template <typename T, typename Read>
std::optional<T> find_one(PgTx& tx, const std::string& sql, const std::string& key, Read read) {
  const pqxx::result rows = tx.exec(sql, key);
  if (rows.empty()) return std::nullopt;
  return read(rows[0]);
}

bool any_project(const std::string& project) {
  return project.empty() || project == proto::kAllProjects;
}

}  // namespace

// One statement reads the job and its finished stages, so both come from one snapshot.
const char* const kPgJobColumns =
    "j.id, j.mission_id, j.state, j.stages, j.options, j.stage, j.progress, j.error, "
    "j.attempts, j.created_at_ms, j.started_at_ms, j.finished_at_ms, "
    "(SELECT COALESCE(json_agg(json_build_array(o.stage, o.seconds) ORDER BY o.seq), '[]') "
    "FROM stage_outputs o WHERE o.job_id = j.id)::text, j.project, j.batch_id, j.worker, m.name";
const char* const kPgMissionColumns =
    "m.id, m.name, m.bundle_blob, COALESCE(m.cad_blob, ''), m.cad_name, m.created_at_ms, "
    "m.project";

namespace {
const std::string kJobSelect =
    std::string("SELECT ") + kPgJobColumns + " FROM jobs j JOIN missions m ON m.id = j.mission_id";
}  // namespace

proto::Job pg_read_job(const pqxx::row& row, int first) {
  auto at = [&](int i) { return row[first + i]; };
  proto::Job job;
  job.id = at(0).as<std::string>();
  job.mission_id = at(1).as<std::string>();
  job.state = proto::job_state_from_string(at(2).as<std::string>(), "jobs.state of " + job.id);
  job.stages = nlohmann::json::parse(at(3).as<std::string>()).get<std::vector<std::string>>();
  job.options = nlohmann::json::parse(at(4).as<std::string>());
  job.stage = at(5).as<std::string>();
  job.progress = at(6).as<double>();
  job.error = at(7).as<std::string>();
  job.attempts = at(8).as<int>();
  job.created_at_ms = at(9).as<int64_t>();
  job.started_at_ms = at(10).as<int64_t>();
  job.finished_at_ms = at(11).as<int64_t>();
  for (const auto& done : nlohmann::json::parse(at(12).as<std::string>())) {
    job.completed_stages.push_back(done[0].get<std::string>());
    job.stage_seconds[done[0].get<std::string>()] = done[1].get<double>();
  }
  job.project = at(13).as<std::string>();
  job.batch_id = at(14).as<std::string>();
  job.worker = at(15).as<std::string>();
  job.mission_name = at(16).as<std::string>();
  std::stable_sort(job.completed_stages.begin(), job.completed_stages.end(),
                   [&](const std::string& a, const std::string& b) {
                     return pipeline_index(job.stages, a) < pipeline_index(job.stages, b);
                   });
  return job;
}

proto::Mission pg_read_mission(const pqxx::row& row, int first) {
  auto at = [&](int i) { return row[first + i]; };
  proto::Mission mission;
  mission.id = at(0).as<std::string>();
  mission.name = at(1).as<std::string>();
  mission.bundle_blob = at(2).as<std::string>();
  mission.cad_blob = at(3).as<std::string>();
  mission.cad_name = at(4).as<std::string>();
  mission.created_at_ms = at(5).as<int64_t>();
  mission.project = at(6).as<std::string>();
  return mission;
}

std::optional<proto::Upload> pg_find_upload(PgTx& tx, const std::string& upload_id) {
  static const std::string sql = std::string(kUploadSelect) + " WHERE id = $1";
  return find_one<proto::Upload>(tx, sql, upload_id, read_upload);
}

std::optional<proto::Mission> pg_find_mission(PgTx& tx, const std::string& mission_id) {
  static const std::string sql = std::string(kMissionSelect) + " WHERE m.id = $1";
  return find_one<proto::Mission>(tx, sql, mission_id,
                                  [](const pqxx::row& row) { return pg_read_mission(row, 0); });
}

std::optional<proto::Job> pg_find_job(PgTx& tx, const std::string& job_id) {
  static const std::string sql = kJobSelect + " WHERE j.id = $1";
  return find_one<proto::Job>(tx, sql, job_id,
                              [](const pqxx::row& row) { return pg_read_job(row, 0); });
}

std::optional<proto::Artifact> pg_find_artifact(PgTx& tx, const std::string& artifact_id) {
  static const std::string sql = std::string(kArtifactSelect) + " WHERE a.id = $1";
  return find_one<proto::Artifact>(tx, sql, artifact_id, read_artifact);
}

std::optional<int64_t> pg_find_blob_size(PgTx& tx, const std::string& sha256) {
  const pqxx::result rows = tx.exec("SELECT size FROM blobs WHERE sha256 = $1", sha256);
  if (rows.empty()) return std::nullopt;
  return rows[0][0].as<int64_t>();
}

std::vector<proto::Job> pg_query_jobs(PgTx& tx, const JobFilter& filter) {
  // '' means "any".
  static const std::string sql =
      kJobSelect +
      " WHERE ($1 = '' OR j.state = $1) AND ($2 = '' OR j.mission_id = $2) "
      "AND ($4 = '' OR j.project = $4) AND ($5 = '' OR j.batch_id = $5) "
      "AND ($6 = '' OR strpos(m.name, $6) > 0) "
      "ORDER BY j.seq DESC LIMIT $3";
  const pqxx::result rows = tx.exec(
      sql, filter.state ? proto::to_string(*filter.state) : std::string(), filter.mission_id,
      filter.limit, any_project(filter.project) ? std::string() : filter.project, filter.batch_id,
      filter.mission_name);
  std::vector<proto::Job> jobs;
  jobs.reserve(rows.size());
  for (const auto& row : rows) jobs.push_back(pg_read_job(row, 0));
  return jobs;
}

std::vector<proto::Mission> pg_query_missions(PgTx& tx, const std::string& name_prefix,
                                              const std::string& project) {
  static const std::string sql = std::string(kMissionSelect) +
                                 " WHERE starts_with(m.name, $1) "
                                 "AND ($2 = '' OR m.project = $2) ORDER BY m.seq DESC";
  const pqxx::result rows =
      tx.exec(sql, name_prefix, any_project(project) ? std::string() : project);
  std::vector<proto::Mission> missions;
  for (const auto& row : rows) missions.push_back(pg_read_mission(row, 0));
  return missions;
}

std::vector<proto::Artifact> pg_job_artifacts(PgTx& tx, const std::string& job_id) {
  static const std::string sql =
      std::string(kArtifactSelect) + " WHERE a.job_id = $1 ORDER BY a.seq";
  const pqxx::result rows = tx.exec(sql, job_id);
  std::vector<proto::Artifact> artifacts;
  for (const auto& row : rows) artifacts.push_back(read_artifact(row));
  return artifacts;
}

std::vector<proto::StageOutput> pg_completed_outputs(PgTx& tx, const proto::Job& job) {
  std::vector<proto::StageOutput> outputs;
  const pqxx::result rows =
      tx.exec("SELECT stage, report, seconds FROM stage_outputs WHERE job_id = $1", job.id);
  for (const auto& row : rows) {
    proto::StageOutput output;
    output.stage = row[0].as<std::string>();
    output.report = nlohmann::json::parse(row[1].as<std::string>());
    output.seconds = row[2].as<double>();
    outputs.push_back(std::move(output));
  }
  if (!outputs.empty())
    for (proto::Artifact& artifact : pg_job_artifacts(tx, job.id))
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

std::string pg_text_array(const std::vector<std::string>& values) {
  std::string out = "{";
  for (size_t i = 0; i < values.size(); ++i) {
    if (i > 0) out += ',';
    out += '"';
    for (char c : values[i]) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
    out += '"';
  }
  out += '}';
  return out;
}

void pg_note_blob_ref(PgTx& tx, const std::string& project, const std::string& sha256) {
  tx.exec("INSERT INTO blob_refs (project, sha256) VALUES ($1, $2) ON CONFLICT DO NOTHING", project,
          sha256);
}

}  // namespace keel::storage
