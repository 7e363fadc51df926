// SqlStore: jobs, the worker protocol (leases, heartbeats, stages, artifacts, finish,
// release, requeue), artifacts and logs.
#include <algorithm>
#include <cmath>

#include "storage/ids.h"
#include "storage/sql_queries.h"
#include "storage/sql_store.h"

namespace keel::storage {

namespace {

// After this many expired leases a job fails instead of being leased again (docs/api.md).
constexpr int kMaxLeaseExpiries = 3;
constexpr int kMaxListLimit = 10000;

LeaseLost lease_lost(const std::string& job_id, const std::string& lease_id) {
  return LeaseLost("job " + job_id + ": lease " + lease_id +
                   " is not the job's current lease (it expired and the job was queued "
                   "again, or the job finished or was retried)");
}

// Invalid unless `stage` is one of the job's stages.
void require_stage_of(const proto::Job& job, const std::string& stage, const std::string& field) {
  if (pipeline_index(job.stages, stage) == job.stages.size())
    throw Invalid(field + ": job " + job.id + " has no stage '" + stage +
                  "' (its stages: " + nlohmann::json(job.stages).dump() + ")");
}

void require_list_limit(int limit) {
  if (limit < 1 || limit > kMaxListLimit)
    throw Invalid("limit: expected 1.." + std::to_string(kMaxListLimit) + ", got " +
                  std::to_string(limit));
}

std::vector<std::string> parse_stages(const std::string& json) {
  return nlohmann::json::parse(json).get<std::vector<std::string>>();
}

// Why a fenced statement matched no row: NotFound, LeaseLost, or Conflict when the lease is
// current but the job is no longer running (canceled).
[[noreturn]] void fence_failure(SqlTx& tx, const std::string& job_id, const std::string& lease_id) {
  auto row = tx.row("SELECT state, lease_id FROM jobs WHERE id = ?1", {job_id});
  if (!row) throw job_not_found(job_id);
  if (row->is_null(1) || row->text(1) != lease_id) throw lease_lost(job_id, lease_id);
  throw Conflict("job " + job_id + " is " + row->text(0) + "; the worker must stop");
}

// Locks the job's row if `lease_id` is its current lease and the job is running, and returns
// the job's id, stages and project; otherwise throws as fence_failure.
proto::Job lock_leased_job(SqlTx& tx, const std::string& job_id, const std::string& lease_id) {
  auto row = tx.row(
      "SELECT stages, project FROM jobs WHERE id = ?1 AND lease_id = ?2 AND state = 'running'"
      "{for_update}",
      {job_id, lease_id});
  if (!row) fence_failure(tx, job_id, lease_id);
  proto::Job job;
  job.id = job_id;
  job.stages = parse_stages(row->text(0));
  job.project = row->text(1);
  return job;
}

// The worker holding the job was heard from now (a heartbeat).
void touch_worker_of(SqlTx& tx, const std::string& job_id, int64_t now_ms) {
  tx.exec(
      "UPDATE workers SET last_seen_ms = ?2, job_id = ?1 "
      "WHERE id = (SELECT worker FROM jobs WHERE id = ?1)",
      {job_id, now_ms});
}

// The worker no longer holds the job (it finished or gave it back).
void release_worker(SqlTx& tx, const std::string& worker, const std::string& job_id,
                    int64_t now_ms) {
  tx.exec("UPDATE workers SET last_seen_ms = ?3, job_id = '' WHERE id = ?1 AND job_id = ?2",
          {worker, job_id, now_ms});
}

// In a write: the job's row changed; `state` is its state now.
void note_job(SqlTx& tx, const std::string& job_id, const std::string& project,
              proto::JobState state) {
  Change change;
  change.job_id = job_id;
  change.project = project;
  change.state = state;
  tx.changes.push_back(std::move(change));
}

// In a write: the job as the write left it, its change noted.
proto::Job changed_job(SqlTx& tx, const std::string& job_id) {
  proto::Job job = require_job(tx, job_id);
  note_job(tx, job.id, job.project, job.state);
  return job;
}

// The worker called the worker protocol now, holding `job_id` ("" = none).
void note_worker(SqlTx& tx, const std::string& worker, const std::string& job_id, int64_t now_ms) {
  if (worker.empty()) return;
  tx.exec(
      "INSERT INTO workers (id, job_id, last_seen_ms) VALUES (?1, ?2, ?3) "
      "ON CONFLICT (id) DO UPDATE SET job_id = excluded.job_id, "
      "last_seen_ms = excluded.last_seen_ms",
      {worker, job_id, now_ms});
}

// Appends lines to the job's log. The caller's transaction holds the job's row (changed it or
// read it {for_update}), so concurrent writers of one log never pick the same number.
void insert_log_lines(SqlTx& tx, const std::string& job_id, const std::vector<std::string>& lines,
                      int64_t now_ms) {
  if (lines.empty()) return;
  auto next = tx.row(
      "SELECT (SELECT COALESCE(MAX(seq) + 1, 0) FROM job_logs WHERE job_id = ?1), project "
      "FROM jobs WHERE id = ?1",
      {job_id});
  if (!next) throw job_not_found(job_id);
  int64_t seq = next->int64(0);
  for (const std::string& line : lines)
    tx.exec("INSERT INTO job_logs (job_id, seq, t_ms, text) VALUES (?1, ?2, ?3, ?4)",
            {job_id, seq++, now_ms, line});
  Change change;
  change.kind = Change::Kind::kLog;
  change.job_id = job_id;
  change.project = next->text(1);
  tx.changes.push_back(std::move(change));
}

// Requeues (or fails, at the last expiry) running jobs whose lease has expired.
int expire_leases(SqlTx& tx, int64_t now_ms) {
  // {skip_locked}: a row another transaction holds (a heartbeat arriving right now, another
  // replica's requeue) is left to it.
  const SqlRows expired = tx.query(
      "SELECT id, lease_id, worker, lease_expiries + 1, project FROM jobs "
      "WHERE state = 'running' AND lease_expires_at_ms <= ?1 "
      "ORDER BY lease_expires_at_ms{skip_locked}",
      {now_ms});
  for (const SqlRow& job : expired) {
    const int64_t expiries = job.int64(3);
    const bool give_up = expiries >= kMaxLeaseExpiries;
    const std::string worker = job.text(2);
    tx.exec(
        "UPDATE jobs SET state = ?2, lease_expiries = ?3, error = ?4, finished_at_ms = ?5, "
        "lease_id = NULL, lease_expires_at_ms = NULL, stage = '', progress = 0 WHERE id = ?1",
        {job.text(0), give_up ? "failed" : "queued", expiries,
         give_up
             ? "lease expired " + std::to_string(expiries) + " times (last worker: " + worker + ")"
             : "",
         give_up ? now_ms : 0});
    insert_log_lines(tx, job.text(0),
                     {"lease " + job.text(1) + " of worker " + worker + " expired" +
                      (give_up ? "; the job failed" : "; the job is queued again")},
                     now_ms);
    note_job(tx, job.text(0), job.text(4),
             give_up ? proto::JobState::kFailed : proto::JobState::kQueued);
  }
  return static_cast<int>(expired.size());
}

// A compare job's inputs: options.compare.job_a, and job_b unless a reprocess job with
// `"compare": true` compares job_a with its own products (it runs other stages first and
// names no job_b); each with its record and artifacts. A job that is missing or of another
// project is never handed out: the inputs stop there and the stage says what is missing.
void add_compare_inputs(SqlTx& tx, proto::Lease& lease) {
  const proto::Job& job = lease.job;
  if (std::find(job.stages.begin(), job.stages.end(), "compare") == job.stages.end()) return;
  if (!job.options.contains("compare") || !job.options["compare"].is_object()) return;
  const nlohmann::json& o = job.options["compare"];
  const bool with_itself = job.stages.size() > 1 && !o.contains("job_b");
  std::vector<const char*> keys = {"job_a"};
  if (!with_itself) keys.push_back("job_b");
  for (const char* key : keys)
    if (!o.contains(key) || !o[key].is_string()) return;
  for (const char* key : keys) {
    auto input = find_job(tx, o[key].get<std::string>());
    if (!input || input->project != job.project) return;
    lease.inputs.push_back({*input, job_artifacts(tx, input->id)});
  }
}

}  // namespace

// --- jobs ---

proto::Job SqlStore::create_job(const proto::JobRequest& request,
                                const std::string& idempotency_key, bool* created) {
  require_pipeline(request.stages, request.options);
  if (idempotency_key.size() > 255) throw Invalid("Idempotency-Key: expected at most 255 bytes");
  auto first_job_of_key = [&](SqlTx& tx) -> std::optional<proto::Job> {
    auto row = tx.row("SELECT id FROM jobs WHERE idempotency_key = ?1", {idempotency_key});
    if (!row) return std::nullopt;
    proto::Job job = require_job(tx, row->text(0));
    if (job.mission_id != request.mission_id || job.stages != request.stages ||
        job.options != request.options)
      throw Conflict("Idempotency-Key '" + idempotency_key + "' was used for job " + job.id +
                     " with a different request");
    if (created) *created = false;
    return job;
  };
  return write([&](SqlTx& tx) {
    if (!idempotency_key.empty())
      if (auto job = first_job_of_key(tx)) return *job;
    const auto mission = find_mission(tx, request.mission_id);
    // Another project's mission is "not found": ids leak nothing across projects.
    if (!mission || (!request.project.empty() && mission->project != request.project))
      throw NotFound("mission_id: mission " + request.mission_id + " not found");
    const std::string job_id = new_id(kJobPrefix);
    // The key is UNIQUE: when another replica inserted it since the check above, this
    // insert does nothing (after waiting for that commit) and its job is the answer.
    if (tx.query("INSERT INTO jobs (id, mission_id, state, stages, options, idempotency_key, "
                 "created_at_ms, project) VALUES (?1, ?2, 'queued', ?3, ?4, NULLIF(?5, ''), ?6, "
                 "?7) ON CONFLICT (idempotency_key) DO NOTHING RETURNING id",
                 {job_id, request.mission_id, nlohmann::json(request.stages).dump(),
                  request.options.dump(), idempotency_key, clock_(), mission->project})
            .empty())
      return *first_job_of_key(tx);
    if (created) *created = true;
    return changed_job(tx, job_id);
  });
}

proto::Job SqlStore::get_job(const std::string& job_id) {
  return read([&](SqlTx& tx) { return require_job(tx, job_id); });
}

std::vector<proto::Job> SqlStore::list_jobs(const JobFilter& filter) {
  require_list_limit(filter.limit);
  return read([&](SqlTx& tx) { return query_jobs(tx, filter); });
}

proto::Job SqlStore::cancel_job(const std::string& job_id) {
  return write([&](SqlTx& tx) {
    auto row = tx.row("SELECT state FROM jobs WHERE id = ?1{for_update}", {job_id});
    if (!row) throw job_not_found(job_id);
    if (proto::is_terminal(proto::job_state_from_string(row->text(0))))
      throw Conflict("job " + job_id + " is " + row->text(0) +
                     "; only queued or running jobs can be canceled");
    // The lease stays, so the worker's next heartbeat is answered "canceled".
    tx.exec("UPDATE jobs SET state = 'canceled', finished_at_ms = ?2 WHERE id = ?1",
            {job_id, clock_()});
    return changed_job(tx, job_id);
  });
}

proto::Job SqlStore::retry_job(const std::string& job_id) {
  return write([&](SqlTx& tx) {
    auto row = tx.row("SELECT state FROM jobs WHERE id = ?1{for_update}", {job_id});
    if (!row) throw job_not_found(job_id);
    if (row->text(0) != "failed" && row->text(0) != "canceled")
      throw Conflict("job " + job_id + " is " + row->text(0) +
                     "; only failed or canceled jobs can be retried");
    // Stage outputs and artifacts stay: the next lease hands them over and the worker
    // resumes after the last completed stage.
    tx.exec(
        "UPDATE jobs SET state = 'queued', stage = '', progress = 0, error = '', "
        "lease_id = NULL, lease_expires_at_ms = NULL, lease_expiries = 0, worker = '', "
        "started_at_ms = 0, finished_at_ms = 0 WHERE id = ?1",
        {job_id});
    return changed_job(tx, job_id);
  });
}

// --- worker protocol ---

int SqlStore::requeue_expired_leases() {
  return write([&](SqlTx& tx) { return expire_leases(tx, clock_()); });
}

std::optional<proto::Lease> SqlStore::lease_job(const proto::LeaseRequest& request) {
  if (request.lease_seconds < 1)
    throw Invalid("lease_seconds: expected >= 1, got " + std::to_string(request.lease_seconds));
  const std::string project = request.project == proto::kAllProjects ? "" : request.project;
  return write([&](SqlTx& tx) -> std::optional<proto::Lease> {
    const int64_t now_ms = clock_();
    expire_leases(tx, now_ms);
    proto::Lease lease;
    lease.lease_id = new_id(kLeasePrefix);
    const int64_t lease_ms = int64_t{request.lease_seconds} * 1000;
    lease.expires_at_ms = now_ms + lease_ms;
    // The oldest queued job, taken in one statement. {skip_locked}: concurrent leases take
    // the next job instead of waiting for this one.
    auto taken = tx.row(
        "UPDATE jobs SET state = 'running', attempts = attempts + 1, lease_id = ?2, "
        "lease_expires_at_ms = ?3, lease_ms = ?4, worker = ?5, stage = '', progress = 0, "
        "started_at_ms = CASE WHEN started_at_ms = 0 THEN ?6 ELSE started_at_ms END "
        "WHERE id = (SELECT id FROM jobs WHERE state = 'queued' AND (?1 = '' OR project = ?1) "
        "ORDER BY seq LIMIT 1{skip_locked}) RETURNING id",
        {project, lease.lease_id, lease.expires_at_ms, lease_ms, request.worker, now_ms});
    note_worker(tx, request.worker, taken ? taken->text(0) : "", now_ms);
    if (!taken) return std::nullopt;
    const std::string job_id = taken->text(0);
    lease.job = changed_job(tx, job_id);
    auto mission = find_mission(tx, lease.job.mission_id);
    if (!mission) throw NotFound("mission " + lease.job.mission_id + " of job " + job_id);
    lease.mission = *mission;
    // Stages finished by earlier attempts (a retry or a requeued job) come with their
    // reports and artifacts.
    if (!lease.job.completed_stages.empty()) lease.completed = completed_outputs(tx, lease.job);
    add_compare_inputs(tx, lease);
    return lease;
  });
}

proto::Job SqlStore::release_job(const std::string& job_id, const std::string& lease_id) {
  return write([&](SqlTx& tx) {
    const int64_t now_ms = clock_();
    // attempts stays: it counts leases taken. A release is not an expiry, so the job does
    // not move toward the "lease expired 3 times" failure.
    auto released = tx.row(
        "UPDATE jobs SET state = 'queued', stage = '', progress = 0, lease_id = NULL, "
        "lease_expires_at_ms = NULL WHERE id = ?1 AND lease_id = ?2 AND state = 'running' "
        "RETURNING worker",
        {job_id, lease_id});
    if (!released) fence_failure(tx, job_id, lease_id);
    insert_log_lines(tx, job_id,
                     {"worker " + released->text(0) + " gave lease " + lease_id +
                      " back; the job is queued again"},
                     now_ms);
    release_worker(tx, released->text(0), job_id, now_ms);
    return changed_job(tx, job_id);
  });
}

proto::HeartbeatReply SqlStore::heartbeat(const std::string& job_id, const proto::Heartbeat& beat) {
  if (!(beat.progress >= 0.0 && beat.progress <= 1.0))
    throw Invalid("progress: expected a fraction in [0, 1]");
  return write([&](SqlTx& tx) {
    const int64_t now_ms = clock_();
    proto::HeartbeatReply reply;
    auto beaten = tx.row(
        "UPDATE jobs SET lease_expires_at_ms = ?3 + lease_ms, stage = ?4, progress = ?5 "
        "WHERE id = ?1 AND lease_id = ?2 AND state = 'running' "
        "RETURNING lease_expires_at_ms, stages, project",
        {job_id, beat.lease_id, now_ms, beat.stage, beat.progress});
    if (!beaten) {
      // A canceled job keeps its lease until the worker hears "canceled" here.
      auto row =
          tx.row("SELECT state, lease_id, lease_expires_at_ms FROM jobs WHERE id = ?1", {job_id});
      if (!row) throw job_not_found(job_id);
      if (row->is_null(1) || row->text(1) != beat.lease_id || row->text(0) != "canceled")
        throw lease_lost(job_id, beat.lease_id);
      reply.canceled = true;
      reply.expires_at_ms = row->int64(2);
      return reply;
    }
    reply.expires_at_ms = beaten->int64(0);
    if (!beat.stage.empty()) {
      proto::Job job;
      job.id = job_id;
      job.stages = parse_stages(beaten->text(1));
      require_stage_of(job, beat.stage, "stage");  // rolls the update back
    }
    insert_log_lines(tx, job_id, beat.log, now_ms);
    note_job(tx, job_id, beaten->text(2), proto::JobState::kRunning);
    touch_worker_of(tx, job_id, now_ms);
    return reply;
  });
}

proto::Artifact SqlStore::add_artifact(const std::string& job_id,
                                       const proto::ArtifactRegistration& registration) {
  // Artifact names become download file names: one plain path component.
  const std::string& name = registration.name;
  if (name.empty() || name.size() > 255 || name == "." || name == "..")
    throw Invalid("name: expected a file name of 1..255 bytes, got '" + name + "'");
  for (char c : name)
    if (c == '/' || c == '\\' || static_cast<unsigned char>(c) < 0x20)
      throw Invalid("name: artifact name '" + name +
                    "' must not contain '/', '\\' or control characters");
  require_sha256(registration.blob, "blob");
  return write([&](SqlTx& tx) {
    const proto::Job job = lock_leased_job(tx, job_id, registration.lease_id);
    require_stage_of(job, registration.stage, "stage");
    const auto size = find_blob_size(tx, registration.blob);
    if (!size) throw NotFound("blob " + registration.blob + " not found (upload it first)");
    proto::Artifact artifact;
    artifact.id = new_id(kArtifactPrefix);
    artifact.job_id = job_id;
    artifact.stage = registration.stage;
    artifact.name = registration.name;
    artifact.sha256 = registration.blob;
    artifact.size = *size;
    artifact.created_at_ms = clock_();
    artifact.project = job.project;
    // A repeated name (a stage rerun) replaces the earlier artifact; ids stay immutable.
    tx.exec("DELETE FROM artifacts WHERE job_id = ?1 AND stage = ?2 AND name = ?3",
            {job_id, artifact.stage, artifact.name});
    tx.exec(
        "INSERT INTO artifacts (id, job_id, stage, name, sha256, size, created_at_ms) "
        "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
        {artifact.id, job_id, artifact.stage, artifact.name, artifact.sha256, artifact.size,
         artifact.created_at_ms});
    note_blob_ref(tx, job.project, artifact.sha256);
    return artifact;
  });
}

void SqlStore::complete_stage(const std::string& job_id, const std::string& stage,
                              const proto::StageCompletion& completion) {
  if (!std::isfinite(completion.seconds) || completion.seconds < 0)
    throw Invalid("seconds: expected a finite duration >= 0");
  write([&](SqlTx& tx) {
    const proto::Job job = lock_leased_job(tx, job_id, completion.lease_id);
    require_stage_of(job, stage, "stage");
    tx.exec(
        "INSERT INTO stage_outputs (job_id, stage, report, seconds, completed_at_ms) "
        "VALUES (?1, ?2, ?3, ?4, ?5) ON CONFLICT (job_id, stage) DO UPDATE SET "
        "report = excluded.report, seconds = excluded.seconds, "
        "completed_at_ms = excluded.completed_at_ms",
        {job_id, stage, completion.report.dump(), completion.seconds, clock_()});
    note_job(tx, job_id, job.project, proto::JobState::kRunning);
  });
}

proto::Job SqlStore::finish_job(const std::string& job_id, const proto::JobFinish& finish,
                                bool succeeded) {
  std::string error;
  if (!succeeded)
    error = finish.error.empty() ? "the worker failed without a message" : finish.error;
  return write([&](SqlTx& tx) {
    const int64_t now_ms = clock_();
    auto finished = tx.row(
        "UPDATE jobs SET state = ?3, error = ?4, finished_at_ms = ?5, stage = '', "
        "progress = CASE WHEN ?3 = 'succeeded' THEN 1 ELSE progress END, "
        "lease_id = NULL, lease_expires_at_ms = NULL "
        "WHERE id = ?1 AND lease_id = ?2 AND state = 'running' RETURNING worker",
        {job_id, finish.lease_id, succeeded ? "succeeded" : "failed", error, now_ms});
    if (!finished) fence_failure(tx, job_id, finish.lease_id);
    release_worker(tx, finished->text(0), job_id, now_ms);
    return changed_job(tx, job_id);
  });
}

// --- artifacts and logs ---

std::vector<proto::Artifact> SqlStore::list_artifacts(const std::string& job_id) {
  return read([&](SqlTx& tx) {
    if (!tx.row("SELECT 1 FROM jobs WHERE id = ?1", {job_id})) throw job_not_found(job_id);
    return job_artifacts(tx, job_id);
  });
}

proto::Artifact SqlStore::get_artifact(const std::string& artifact_id) {
  auto artifact = read([&](SqlTx& tx) { return find_artifact(tx, artifact_id); });
  if (!artifact) throw NotFound("artifact " + artifact_id + " not found");
  return *artifact;
}

void SqlStore::append_log(const std::string& job_id, const std::vector<std::string>& lines) {
  write([&](SqlTx& tx) {
    if (!tx.row("SELECT 1 FROM jobs WHERE id = ?1{for_update}", {job_id}))
      throw job_not_found(job_id);
    insert_log_lines(tx, job_id, lines, clock_());
  });
}

proto::LogPage SqlStore::read_log(const std::string& job_id, int64_t from, int limit) {
  if (from < 0) throw Invalid("from: expected >= 0, got " + std::to_string(from));
  require_list_limit(limit);
  return read([&](SqlTx& tx) {
    if (!tx.row("SELECT 1 FROM jobs WHERE id = ?1", {job_id})) throw job_not_found(job_id);
    proto::LogPage page;
    page.next = from;
    for (const SqlRow& row : tx.query("SELECT seq, t_ms, text FROM job_logs "
                                      "WHERE job_id = ?1 AND seq >= ?2 ORDER BY seq LIMIT ?3",
                                      {job_id, from, int64_t{limit}})) {
      page.lines.push_back({row.int64(0), row.int64(1), row.text(2)});
      page.next = page.lines.back().seq + 1;
    }
    return page;
  });
}

}  // namespace keel::storage
