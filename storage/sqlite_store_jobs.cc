// SqliteStore: jobs, the worker protocol (leases, heartbeats, stages, artifacts, finish),
// artifacts and logs.
#include <cmath>

#include "storage/ids.h"
#include "storage/sqlite_queries.h"
#include "storage/sqlite_store.h"
#include "storage/store_rules.h"

namespace keel::storage {

namespace {

using namespace rules;

proto::Job require_job(Database& db, const std::string& job_id) {
  auto job = find_job(db, job_id);
  if (!job) throw job_not_found(job_id);
  return *job;
}

}  // namespace

// --- jobs ---

proto::Job SqliteStore::create_job(const proto::JobRequest& request,
                                   const std::string& idempotency_key, bool* created) {
  require_pipeline(request.stages, request.options);
  require_idempotency_key(idempotency_key);
  return write([&](Database& db) {
    if (!idempotency_key.empty()) {
      auto existing = db.cached("SELECT id FROM jobs WHERE idempotency_key = ?1");
      existing->bind_text(1, idempotency_key);
      if (existing->step()) {
        proto::Job job = require_job(db, existing->column_text(0));
        if (!same_request(job, request))
          throw Conflict("Idempotency-Key '" + idempotency_key + "' was used for job " + job.id +
                         " with a different request");
        if (created) *created = false;
        return job;
      }
    }
    const auto mission = find_mission(db, request.mission_id);
    // Another project's mission is "not found": ids leak nothing across projects.
    if (!mission || (!request.project.empty() && mission->project != request.project))
      throw NotFound("mission_id: mission " + request.mission_id + " not found");
    const std::string job_id = new_id(kJobPrefix);
    auto insert = db.cached(
        "INSERT INTO jobs (id, mission_id, state, stages, options, idempotency_key, "
        "created_at_ms, project) VALUES (?1, ?2, 'queued', ?3, ?4, ?5, ?6, ?7)");
    insert->bind_text(1, job_id)
        .bind_text(2, request.mission_id)
        .bind_text(3, nlohmann::json(request.stages).dump())
        .bind_text(4, request.options.dump())
        .bind_text_or_null(5, idempotency_key)
        .bind_int64(6, clock_())
        .bind_text(7, mission->project)
        .run();
    if (created) *created = true;
    note_job(db, job_id);
    return require_job(db, job_id);
  });
}

proto::Job SqliteStore::get_job(const std::string& job_id) {
  return read([&](Database& db) { return require_job(db, job_id); });
}

std::vector<proto::Job> SqliteStore::list_jobs(const JobFilter& filter) {
  require_list_limit(filter.limit);
  return read([&](Database& db) { return query_jobs(db, filter); });
}

proto::Job SqliteStore::cancel_job(const std::string& job_id) {
  return write([&](Database& db) {
    const proto::Job job = require_job(db, job_id);
    if (proto::is_terminal(job.state))
      throw Conflict("job " + job_id + " is " + proto::to_string(job.state) +
                     "; only queued or running jobs can be canceled");
    // The lease stays, so the worker's next heartbeat is answered "canceled".
    auto statement =
        db.cached("UPDATE jobs SET state = 'canceled', finished_at_ms = ?2 WHERE id = ?1");
    statement->bind_text(1, job_id).bind_int64(2, clock_()).run();
    note_job(db, job_id);
    return require_job(db, job_id);
  });
}

proto::Job SqliteStore::retry_job(const std::string& job_id) {
  return write([&](Database& db) {
    const proto::Job job = require_job(db, job_id);
    if (job.state != proto::JobState::kFailed && job.state != proto::JobState::kCanceled)
      throw Conflict("job " + job_id + " is " + proto::to_string(job.state) +
                     "; only failed or canceled jobs can be retried");
    // Stage outputs and artifacts stay: the next lease hands them over and the worker
    // resumes after the last completed stage.
    auto statement = db.cached(
        "UPDATE jobs SET state = 'queued', stage = '', progress = 0, error = '', "
        "lease_id = NULL, lease_expires_at_ms = NULL, lease_expiries = 0, worker = '', "
        "started_at_ms = 0, finished_at_ms = 0 WHERE id = ?1");
    statement->bind_text(1, job_id).run();
    note_job(db, job_id);
    return require_job(db, job_id);
  });
}

// --- worker protocol ---

int SqliteStore::expire_leases(Database& db, int64_t now_ms) {
  struct Expired {
    std::string job_id, lease_id, worker;
    int expiries;
  };
  std::vector<Expired> expired;
  {
    auto statement = db.cached(
        "SELECT id, lease_id, worker, lease_expiries FROM jobs "
        "WHERE state = 'running' AND lease_expires_at_ms <= ?1");
    statement->bind_int64(1, now_ms);
    while (statement->step())
      expired.push_back({statement->column_text(0), statement->column_text(1),
                         statement->column_text(2),
                         static_cast<int>(statement->column_int64(3)) + 1});
  }
  for (const Expired& job : expired) {
    const bool give_up = job.expiries >= kMaxLeaseExpiries;
    auto statement = db.cached(
        "UPDATE jobs SET state = ?2, lease_expiries = ?3, error = ?4, finished_at_ms = ?5, "
        "lease_id = NULL, lease_expires_at_ms = NULL, stage = '', progress = 0 WHERE id = ?1");
    statement->bind_text(1, job.job_id)
        .bind_text(2, give_up ? "failed" : "queued")
        .bind_int64(3, job.expiries)
        .bind_text(4, give_up ? expired_lease_error(job.expiries, job.worker) : "")
        .bind_int64(5, give_up ? now_ms : 0)
        .run();
    insert_log_lines(db, job.job_id, {expired_lease_line(job.lease_id, job.worker, give_up)},
                     now_ms);
    note_job(db, job.job_id);
  }
  return static_cast<int>(expired.size());
}

int SqliteStore::requeue_expired_leases() {
  return write([&](Database& db) { return expire_leases(db, clock_()); });
}

std::optional<proto::Lease> SqliteStore::lease_job(const proto::LeaseRequest& request) {
  require_lease_seconds(request.lease_seconds);
  return write([&](Database& db) -> std::optional<proto::Lease> {
    const int64_t now_ms = clock_();
    expire_leases(db, now_ms);
    std::string job_id;
    {
      const bool any_project = request.project.empty() || request.project == proto::kAllProjects;
      auto oldest = db.cached(
          "SELECT id FROM jobs WHERE state = 'queued' AND (?1 IS NULL OR project = ?1) "
          "ORDER BY seq LIMIT 1");
      oldest->bind_text_or_null(1, any_project ? std::string() : request.project);
      if (!oldest->step()) {
        note_worker(db, request.worker, "", now_ms);
        return std::nullopt;
      }
      job_id = oldest->column_text(0);
    }
    proto::Lease lease;
    lease.lease_id = new_id(kLeasePrefix);
    const int64_t lease_ms = int64_t{request.lease_seconds} * 1000;
    lease.expires_at_ms = now_ms + lease_ms;
    auto statement = db.cached(
        "UPDATE jobs SET state = 'running', attempts = attempts + 1, lease_id = ?2, "
        "lease_expires_at_ms = ?3, lease_ms = ?4, worker = ?5, stage = '', progress = 0, "
        "started_at_ms = CASE WHEN started_at_ms = 0 THEN ?6 ELSE started_at_ms END "
        "WHERE id = ?1");
    statement->bind_text(1, job_id)
        .bind_text(2, lease.lease_id)
        .bind_int64(3, lease.expires_at_ms)
        .bind_int64(4, lease_ms)
        .bind_text(5, request.worker)
        .bind_int64(6, now_ms)
        .run();
    note_worker(db, request.worker, job_id, now_ms);
    note_job(db, job_id);
    lease.job = require_job(db, job_id);
    auto mission = find_mission(db, lease.job.mission_id);
    if (!mission) throw NotFound("mission " + lease.job.mission_id + " of job " + job_id);
    lease.mission = *mission;
    lease.completed = completed_outputs(db, lease.job);
    return lease;
  });
}

proto::Job SqliteStore::require_running_lease(Database& db, const std::string& job_id,
                                              const std::string& lease_id) {
  auto statement = db.cached("SELECT state, lease_id FROM jobs WHERE id = ?1");
  statement->bind_text(1, job_id);
  if (!statement->step()) throw job_not_found(job_id);
  const std::string state = statement->column_text(0);
  if (statement->column_is_null(1) || statement->column_text(1) != lease_id)
    throw lease_lost(job_id, lease_id);
  if (state != "running")
    throw Conflict("job " + job_id + " is " + state + "; the worker must stop");
  return require_job(db, job_id);
}

proto::HeartbeatReply SqliteStore::heartbeat(const std::string& job_id,
                                             const proto::Heartbeat& beat) {
  require_progress(beat.progress);
  return write([&](Database& db) {
    const int64_t now_ms = clock_();
    proto::HeartbeatReply reply;
    {
      auto statement = db.cached(
          "SELECT state, lease_id, lease_expires_at_ms, lease_ms FROM jobs WHERE id = ?1");
      statement->bind_text(1, job_id);
      if (!statement->step()) throw job_not_found(job_id);
      const std::string state = statement->column_text(0);
      if (statement->column_is_null(1) || statement->column_text(1) != beat.lease_id ||
          (state != "running" && state != "canceled"))
        throw lease_lost(job_id, beat.lease_id);
      if (state == "canceled") {
        reply.canceled = true;
        reply.expires_at_ms = statement->column_int64(2);
        return reply;
      }
      reply.expires_at_ms = now_ms + statement->column_int64(3);
    }
    if (!beat.stage.empty()) require_stage_of(require_job(db, job_id), beat.stage, "stage");
    auto update = db.cached(
        "UPDATE jobs SET lease_expires_at_ms = ?2, stage = ?3, progress = ?4 WHERE id = ?1");
    update->bind_text(1, job_id)
        .bind_int64(2, reply.expires_at_ms)
        .bind_text(3, beat.stage)
        .bind_double(4, beat.progress)
        .run();
    insert_log_lines(db, job_id, beat.log, now_ms);
    note_job(db, job_id);
    touch_worker_of(db, job_id, now_ms);
    return reply;
  });
}

proto::Artifact SqliteStore::add_artifact(const std::string& job_id,
                                          const proto::ArtifactRegistration& registration) {
  require_artifact_name(registration.name);
  if (!proto::is_sha256_hex(registration.blob))
    throw Invalid("blob: expected 64 lowercase hex digits (SHA-256), got '" + registration.blob +
                  "'");
  return write([&](Database& db) {
    const proto::Job job = require_running_lease(db, job_id, registration.lease_id);
    require_stage_of(job, registration.stage, "stage");
    const auto size = find_blob_size(db, registration.blob);
    if (!size) throw NotFound("blob " + registration.blob + " not found (upload it first)");
    proto::Artifact artifact;
    artifact.id = new_id(kArtifactPrefix);
    artifact.job_id = job_id;
    artifact.stage = registration.stage;
    artifact.name = registration.name;
    artifact.sha256 = registration.blob;
    artifact.size = *size;
    artifact.created_at_ms = clock_();
    // A repeated name (a stage rerun) replaces the earlier artifact; ids stay immutable.
    auto remove = db.cached("DELETE FROM artifacts WHERE job_id = ?1 AND stage = ?2 AND name = ?3");
    remove->bind_text(1, job_id).bind_text(2, artifact.stage).bind_text(3, artifact.name).run();
    auto insert = db.cached(
        "INSERT INTO artifacts (id, job_id, stage, name, sha256, size, created_at_ms) "
        "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
    insert->bind_text(1, artifact.id)
        .bind_text(2, job_id)
        .bind_text(3, artifact.stage)
        .bind_text(4, artifact.name)
        .bind_text(5, artifact.sha256)
        .bind_int64(6, artifact.size)
        .bind_int64(7, artifact.created_at_ms)
        .run();
    note_blob_ref(db, job.project, artifact.sha256);
    return artifact;
  });
}

void SqliteStore::complete_stage(const std::string& job_id, const std::string& stage,
                                 const proto::StageCompletion& completion) {
  if (!std::isfinite(completion.seconds) || completion.seconds < 0)
    throw Invalid("seconds: expected a finite duration >= 0");
  write([&](Database& db) {
    const proto::Job job = require_running_lease(db, job_id, completion.lease_id);
    require_stage_of(job, stage, "stage");
    auto statement = db.cached(
        "INSERT INTO stage_outputs (job_id, stage, report, seconds, completed_at_ms) "
        "VALUES (?1, ?2, ?3, ?4, ?5) ON CONFLICT (job_id, stage) DO UPDATE SET "
        "report = excluded.report, seconds = excluded.seconds, "
        "completed_at_ms = excluded.completed_at_ms");
    statement->bind_text(1, job_id)
        .bind_text(2, stage)
        .bind_text(3, completion.report.dump())
        .bind_double(4, completion.seconds)
        .bind_int64(5, clock_())
        .run();
    note_job(db, job_id);
  });
}

proto::Job SqliteStore::finish_job(const std::string& job_id, const proto::JobFinish& finish,
                                   bool succeeded) {
  return write([&](Database& db) {
    require_running_lease(db, job_id, finish.lease_id);
    const std::string error = finish_error(finish, succeeded);
    auto statement = db.cached(
        "UPDATE jobs SET state = ?2, error = ?3, finished_at_ms = ?4, stage = '', "
        "progress = CASE WHEN ?2 = 'succeeded' THEN 1 ELSE progress END, "
        "lease_id = NULL, lease_expires_at_ms = NULL WHERE id = ?1");
    statement->bind_text(1, job_id)
        .bind_text(2, succeeded ? "succeeded" : "failed")
        .bind_text(3, error)
        .bind_int64(4, clock_())
        .run();
    note_job(db, job_id);
    release_worker_of(db, job_id, clock_());
    return require_job(db, job_id);
  });
}

proto::Job SqliteStore::release_job(const std::string& job_id, const std::string& lease_id) {
  return write([&](Database& db) {
    const proto::Job job = require_running_lease(db, job_id, lease_id);
    const int64_t now_ms = clock_();
    // attempts stays: it counts leases taken. A release is not an expiry, so the job does
    // not move toward the "lease expired 3 times" failure.
    auto statement = db.cached(
        "UPDATE jobs SET state = 'queued', stage = '', progress = 0, lease_id = NULL, "
        "lease_expires_at_ms = NULL WHERE id = ?1");
    statement->bind_text(1, job_id).run();
    insert_log_lines(db, job_id, {released_lease_line(job.worker, lease_id)}, now_ms);
    release_worker_of(db, job_id, now_ms);
    note_job(db, job_id);
    return require_job(db, job_id);
  });
}

void SqliteStore::touch_worker_of(Database& db, const std::string& job_id, int64_t now_ms) {
  auto statement = db.cached(
      "UPDATE workers SET last_seen_ms = ?2, job_id = ?1 "
      "WHERE id = (SELECT worker FROM jobs WHERE id = ?1)");
  statement->bind_text(1, job_id).bind_int64(2, now_ms).run();
}

void SqliteStore::release_worker_of(Database& db, const std::string& job_id, int64_t now_ms) {
  auto statement = db.cached(
      "UPDATE workers SET last_seen_ms = ?2, job_id = '' "
      "WHERE id = (SELECT worker FROM jobs WHERE id = ?1) AND job_id = ?1");
  statement->bind_text(1, job_id).bind_int64(2, now_ms).run();
}

// --- artifacts and logs ---

std::vector<proto::Artifact> SqliteStore::list_artifacts(const std::string& job_id) {
  return read([&](Database& db) {
    Transaction snapshot(db, Transaction::Mode::kDeferred);
    if (!find_job(db, job_id)) throw job_not_found(job_id);
    auto artifacts = job_artifacts(db, job_id);
    snapshot.commit();
    return artifacts;
  });
}

proto::Artifact SqliteStore::get_artifact(const std::string& artifact_id) {
  auto artifact = read([&](Database& db) { return find_artifact(db, artifact_id); });
  if (!artifact) throw NotFound("artifact " + artifact_id + " not found");
  return *artifact;
}

void SqliteStore::insert_log_lines(Database& db, const std::string& job_id,
                                   const std::vector<std::string>& lines, int64_t now_ms) {
  if (lines.empty()) return;
  int64_t seq = 0;
  {
    auto next = db.cached("SELECT COALESCE(MAX(seq) + 1, 0) FROM job_logs WHERE job_id = ?1");
    next->bind_text(1, job_id);
    next->step();
    seq = next->column_int64(0);
  }
  auto insert = db.cached("INSERT INTO job_logs (job_id, seq, t_ms, text) VALUES (?1, ?2, ?3, ?4)");
  for (const std::string& line : lines) {
    insert->bind_text(1, job_id).bind_int64(2, seq++).bind_int64(3, now_ms).bind_text(4, line);
    insert->run();
    insert->reset();
  }
  note_log(db, job_id);
}

void SqliteStore::append_log(const std::string& job_id, const std::vector<std::string>& lines) {
  write([&](Database& db) {
    if (!find_job(db, job_id)) throw job_not_found(job_id);
    insert_log_lines(db, job_id, lines, clock_());
  });
}

proto::LogPage SqliteStore::read_log(const std::string& job_id, int64_t from, int limit) {
  if (from < 0) throw Invalid("from: expected >= 0, got " + std::to_string(from));
  require_list_limit(limit);
  return read([&](Database& db) {
    Transaction snapshot(db, Transaction::Mode::kDeferred);
    if (!find_job(db, job_id)) throw job_not_found(job_id);
    proto::LogPage page;
    page.next = from;
    {
      auto statement = db.cached(
          "SELECT seq, t_ms, text FROM job_logs WHERE job_id = ?1 AND seq >= ?2 "
          "ORDER BY seq LIMIT ?3");
      statement->bind_text(1, job_id).bind_int64(2, from).bind_int64(3, limit);
      while (statement->step()) {
        page.lines.push_back(
            {statement->column_int64(0), statement->column_int64(1), statement->column_text(2)});
        page.next = page.lines.back().seq + 1;
      }
    }
    snapshot.commit();
    return page;
  });
}

}  // namespace keel::storage
