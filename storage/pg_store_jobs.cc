// PgStore: jobs, the worker protocol (leases, heartbeats, stages, artifacts, finish,
// release, requeue), artifacts and logs.
//
// Every worker call is fenced by its lease: the statement that changes the job names the
// job, the lease id and state 'running' in its WHERE clause (or locks the row only under
// that condition), so a stale worker's call changes nothing; only then is the reason read
// for the error (fence_failure).
#include <cmath>
#include <tuple>

#include "storage/ids.h"
#include "storage/pg_queries.h"
#include "storage/pg_store.h"
#include "storage/store_rules.h"

namespace keel::storage {

namespace {

proto::Job require_job(PgTx& tx, const std::string& job_id) {
  auto job = pg_find_job(tx, job_id);
  if (!job) throw rules::job_not_found(job_id);
  return *job;
}

// Why a fenced statement matched no row: NotFound, LeaseLost, or Conflict when the lease is
// current but the job is no longer running (canceled).
[[noreturn]] void fence_failure(PgTx& tx, const std::string& job_id, const std::string& lease_id) {
  const pqxx::result rows = tx.exec("SELECT state, lease_id FROM jobs WHERE id = $1", job_id);
  if (rows.empty()) throw rules::job_not_found(job_id);
  if (rows[0][1].is_null() || rows[0][1].as<std::string>() != lease_id)
    throw rules::lease_lost(job_id, lease_id);
  throw Conflict("job " + job_id + " is " + rows[0][0].as<std::string>() +
                 "; the worker must stop");
}

// Locks the job's row if `lease_id` is its current lease and it is running; returns its
// stages. Otherwise throws as fence_failure.
std::vector<std::string> lock_leased_job(PgTx& tx, const std::string& job_id,
                                         const std::string& lease_id) {
  const pqxx::result rows = tx.exec(
      "SELECT stages FROM jobs WHERE id = $1 AND lease_id = $2 AND state = 'running' "
      "FOR NO KEY UPDATE",
      job_id, lease_id);
  if (rows.empty()) fence_failure(tx, job_id, lease_id);
  return nlohmann::json::parse(rows[0][0].as<std::string>()).get<std::vector<std::string>>();
}

// PostgreSQL text cannot hold NUL bytes; a log line keeps everything else.
std::string without_nul(std::string text) {
  for (char& c : text)
    if (c == '\0') c = ' ';
  return text;
}

Change job_change(const std::string& job_id, const std::string& project, proto::JobState state) {
  Change change;
  change.kind = Change::Kind::kJob;
  change.job_id = job_id;
  change.project = project;
  change.state = state;
  return change;
}

}  // namespace

// --- jobs ---

proto::Job PgStore::create_job(const proto::JobRequest& request, const std::string& idempotency_key,
                               bool* created) {
  rules::require_pipeline(request.stages, request.options);
  rules::require_idempotency_key(idempotency_key);
  auto first_job_of_key = [&](PgTx& tx) -> std::optional<proto::Job> {
    const pqxx::result rows =
        tx.exec("SELECT id FROM jobs WHERE idempotency_key = $1", idempotency_key);
    if (rows.empty()) return std::nullopt;
    proto::Job job = require_job(tx, rows[0][0].as<std::string>());
    if (!rules::same_request(job, request))
      throw Conflict("Idempotency-Key '" + idempotency_key + "' was used for job " + job.id +
                     " with a different request");
    return job;
  };
  return write([&](PgTx& tx, Changes& changes) {
    if (!idempotency_key.empty())
      if (auto job = first_job_of_key(tx)) {
        if (created) *created = false;
        return *job;
      }
    const auto mission = pg_find_mission(tx, request.mission_id);
    // Another project's mission is "not found": ids leak nothing across projects.
    if (!mission || (!request.project.empty() && mission->project != request.project))
      throw NotFound("mission_id: mission " + request.mission_id + " not found");
    const std::string job_id = new_id(kJobPrefix);
    // The key is UNIQUE: when another replica inserted it since the check above, this
    // insert does nothing (after waiting for that commit) and its job is the answer.
    const pqxx::result inserted = tx.exec(
        "INSERT INTO jobs (id, mission_id, state, stages, options, idempotency_key, "
        "created_at_ms, project) VALUES ($1, $2, 'queued', $3, $4, NULLIF($5, ''), $6, $7) "
        "ON CONFLICT (idempotency_key) DO NOTHING RETURNING id",
        job_id, request.mission_id, nlohmann::json(request.stages).dump(), request.options.dump(),
        idempotency_key, clock_(), mission->project);
    if (inserted.empty()) {
      if (created) *created = false;
      return *first_job_of_key(tx);
    }
    if (created) *created = true;
    changes.push_back(job_change(job_id, mission->project, proto::JobState::kQueued));
    return require_job(tx, job_id);
  });
}

proto::Job PgStore::get_job(const std::string& job_id) {
  return read([&](PgTx& tx) { return require_job(tx, job_id); });
}

std::vector<proto::Job> PgStore::list_jobs(const JobFilter& filter) {
  rules::require_list_limit(filter.limit);
  return read([&](PgTx& tx) { return pg_query_jobs(tx, filter); });
}

proto::Job PgStore::cancel_job(const std::string& job_id) {
  return write([&](PgTx& tx, Changes& changes) {
    const pqxx::result rows =
        tx.exec("SELECT state FROM jobs WHERE id = $1 FOR NO KEY UPDATE", job_id);
    if (rows.empty()) throw rules::job_not_found(job_id);
    const std::string state = rows[0][0].as<std::string>();
    if (proto::is_terminal(proto::job_state_from_string(state)))
      throw Conflict("job " + job_id + " is " + state +
                     "; only queued or running jobs can be canceled");
    // The lease stays, so the worker's next heartbeat is answered "canceled".
    tx.exec("UPDATE jobs SET state = 'canceled', finished_at_ms = $2 WHERE id = $1", job_id,
            clock_());
    note_job(tx, changes, job_id);
    return require_job(tx, job_id);
  });
}

proto::Job PgStore::retry_job(const std::string& job_id) {
  return write([&](PgTx& tx, Changes& changes) {
    const pqxx::result rows =
        tx.exec("SELECT state FROM jobs WHERE id = $1 FOR NO KEY UPDATE", job_id);
    if (rows.empty()) throw rules::job_not_found(job_id);
    const std::string state = rows[0][0].as<std::string>();
    if (state != "failed" && state != "canceled")
      throw Conflict("job " + job_id + " is " + state +
                     "; only failed or canceled jobs can be retried");
    // Stage outputs and artifacts stay: the next lease hands them over and the worker
    // resumes after the last completed stage.
    tx.exec(
        "UPDATE jobs SET state = 'queued', stage = '', progress = 0, error = '', "
        "lease_id = NULL, lease_expires_at_ms = NULL, lease_expiries = 0, worker = '', "
        "started_at_ms = 0, finished_at_ms = 0 WHERE id = $1",
        job_id);
    note_job(tx, changes, job_id);
    return require_job(tx, job_id);
  });
}

// --- worker protocol ---

int PgStore::expire_leases(PgTx& tx, Changes& changes, int64_t now_ms) {
  // One UPDATE requeues (or, at the last expiry, fails) every expired lease. SKIP LOCKED:
  // a row another transaction holds (a heartbeat arriving right now, another replica's
  // requeue) is left to it. The failure message is rules::expired_lease_error's.
  const pqxx::result expired = tx.exec(
      "WITH expired AS MATERIALIZED ("
      "  SELECT id, lease_id, worker, lease_expiries + 1 AS expiries FROM jobs"
      "  WHERE state = 'running' AND lease_expires_at_ms <= $1"
      "  ORDER BY lease_expires_at_ms FOR UPDATE SKIP LOCKED) "
      "UPDATE jobs j SET"
      "  state = CASE WHEN e.expiries >= $2 THEN 'failed' ELSE 'queued' END,"
      "  lease_expiries = e.expiries,"
      "  error = CASE WHEN e.expiries >= $2 THEN 'lease expired ' || e.expiries ||"
      "          ' times (last worker: ' || e.worker || ')' ELSE '' END,"
      "  finished_at_ms = CASE WHEN e.expiries >= $2 THEN $1 ELSE 0 END,"
      "  lease_id = NULL, lease_expires_at_ms = NULL, stage = '', progress = 0,"
      "  log_next = j.log_next + 1 "
      "FROM expired e WHERE j.id = e.id "
      "RETURNING j.id, j.project, j.state, j.log_next - 1, e.lease_id, e.worker",
      now_ms, rules::kMaxLeaseExpiries);
  if (expired.empty()) return 0;
  std::vector<std::string> ids, seqs, lines;
  for (const auto& row : expired) {
    const std::string job_id = row[0].as<std::string>();
    const auto state = proto::job_state_from_string(row[2].as<std::string>());
    ids.push_back(job_id);
    seqs.push_back(row[3].as<std::string>());
    lines.push_back(rules::expired_lease_line(row[4].as<std::string>(), row[5].as<std::string>(),
                                              state == proto::JobState::kFailed));
    changes.push_back(job_change(job_id, row[1].as<std::string>(), state));
    Change logged = changes.back();
    logged.kind = Change::Kind::kLog;
    changes.push_back(logged);
  }
  tx.exec(
      "INSERT INTO job_logs (job_id, seq, t_ms, text) "
      "SELECT id, seq, $4, text FROM unnest($1::text[], $2::bigint[], $3::text[]) "
      "AS l(id, seq, text)",
      pg_text_array(ids), pg_text_array(seqs), pg_text_array(lines), now_ms);
  return static_cast<int>(expired.size());
}

int PgStore::requeue_expired_leases() {
  return write([&](PgTx& tx, Changes& changes) { return expire_leases(tx, changes, clock_()); });
}

std::optional<proto::Lease> PgStore::lease_job(const proto::LeaseRequest& request) {
  rules::require_lease_seconds(request.lease_seconds);
  const bool any_project = request.project.empty() || request.project == proto::kAllProjects;
  // One statement, committed alone: the oldest queued job no other transaction holds is
  // locked (SKIP LOCKED: concurrent leases take the next one instead of waiting), taken,
  // the worker recorded as seen, and the job and its mission returned, with a flag telling
  // whether some running job's lease has expired.
  static const std::string sql =
      std::string(
          "WITH next AS MATERIALIZED ("
          "  SELECT id FROM jobs WHERE state = 'queued' AND ($1 = '' OR project = $1)"
          "  ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED),"
          "taken AS ("
          "  UPDATE jobs j SET state = 'running', attempts = attempts + 1, lease_id = $2,"
          "    lease_expires_at_ms = $3, lease_ms = $4, worker = $5, stage = '', progress = 0,"
          "    started_at_ms = CASE WHEN started_at_ms = 0 THEN $6 ELSE started_at_ms END"
          "  FROM next WHERE j.id = next.id RETURNING j.*),"
          "seen AS ("
          "  INSERT INTO workers (id, job_id, last_seen_ms)"
          "  SELECT $5, COALESCE((SELECT id FROM taken), ''), $6 WHERE $5 <> ''"
          "  ON CONFLICT (id) DO UPDATE SET job_id = excluded.job_id,"
          "    last_seen_ms = excluded.last_seen_ms) "
          "SELECT EXISTS (SELECT 1 FROM jobs WHERE state = 'running' AND "
          "lease_expires_at_ms <= $6), ") +
      kPgJobColumns + ", " + kPgMissionColumns +
      " FROM (SELECT 1) AS one LEFT JOIN (taken j JOIN missions m ON m.id = j.mission_id) "
      "ON true";
  auto take = [&](int64_t now_ms,
                  Changes& changes) -> std::pair<std::optional<proto::Lease>, bool> {
    proto::Lease lease;
    lease.lease_id = new_id(kLeasePrefix);
    const int64_t lease_ms = int64_t{request.lease_seconds} * 1000;
    lease.expires_at_ms = now_ms + lease_ms;
    return pool_.autocommit([&](PgTx& tx) -> std::pair<std::optional<proto::Lease>, bool> {
      changes.clear();
      const pqxx::row row =
          tx.exec(sql, any_project ? std::string() : request.project, lease.lease_id,
                  lease.expires_at_ms, lease_ms, request.worker, now_ms)[0];
      const bool expired = row[0].as<bool>();
      if (row[1].is_null()) return {std::nullopt, expired};
      lease.job = pg_read_job(row, 1);
      lease.mission = pg_read_mission(row, 1 + kPgJobColumnCount);
      // Stages finished by earlier attempts (a retry or a requeued job) come with their
      // reports and artifacts.
      if (!lease.job.completed_stages.empty())
        lease.completed = pg_completed_outputs(tx, lease.job);
      changes.push_back(job_change(lease.job.id, lease.job.project, proto::JobState::kRunning));
      return {lease, expired};
    });
  };
  Changes changes;
  auto [lease, expired] = take(clock_(), changes);
  committed(changes);
  // Expired leases are requeued first (and, when nothing else was queued, the requeued job
  // is leased now); each replica's requeue loop does the same on its own.
  if (expired && requeue_expired_leases() > 0 && !lease) {
    std::tie(lease, expired) = take(clock_(), changes);
    committed(changes);
  }
  return lease;
}

proto::Job PgStore::release_job(const std::string& job_id, const std::string& lease_id) {
  return write([&](PgTx& tx, Changes& changes) {
    const int64_t now_ms = clock_();
    // attempts stays: it counts leases taken. A release is not an expiry, so the job does
    // not move toward the "lease expired 3 times" failure.
    const pqxx::result released = tx.exec(
        "UPDATE jobs SET state = 'queued', stage = '', progress = 0, lease_id = NULL, "
        "lease_expires_at_ms = NULL WHERE id = $1 AND lease_id = $2 AND state = 'running' "
        "RETURNING worker",
        job_id, lease_id);
    if (released.empty()) fence_failure(tx, job_id, lease_id);
    const std::string worker = released[0][0].as<std::string>();
    insert_log_lines(tx, changes, job_id, {rules::released_lease_line(worker, lease_id)}, now_ms);
    release_worker_of(tx, job_id, now_ms);
    note_job(tx, changes, job_id);
    return require_job(tx, job_id);
  });
}

proto::HeartbeatReply PgStore::heartbeat(const std::string& job_id, const proto::Heartbeat& beat) {
  rules::require_progress(beat.progress);
  return write([&](PgTx& tx, Changes& changes) {
    const int64_t now_ms = clock_();
    proto::HeartbeatReply reply;
    const pqxx::result beaten = tx.exec(
        "UPDATE jobs SET lease_expires_at_ms = $3 + lease_ms, stage = $4, progress = $5 "
        "WHERE id = $1 AND lease_id = $2 AND state = 'running' "
        "RETURNING lease_expires_at_ms, stages, project",
        job_id, beat.lease_id, now_ms, beat.stage, beat.progress);
    if (beaten.empty()) {
      // A canceled job keeps its lease until the worker hears "canceled" here.
      const pqxx::result rows =
          tx.exec("SELECT state, lease_id, lease_expires_at_ms FROM jobs WHERE id = $1", job_id);
      if (rows.empty()) throw rules::job_not_found(job_id);
      if (rows[0][1].is_null() || rows[0][1].as<std::string>() != beat.lease_id ||
          rows[0][0].as<std::string>() != "canceled")
        throw rules::lease_lost(job_id, beat.lease_id);
      reply.canceled = true;
      reply.expires_at_ms = rows[0][2].as<int64_t>();
      return reply;
    }
    reply.expires_at_ms = beaten[0][0].as<int64_t>();
    if (!beat.stage.empty()) {
      proto::Job stages;
      stages.id = job_id;
      stages.stages =
          nlohmann::json::parse(beaten[0][1].as<std::string>()).get<std::vector<std::string>>();
      rules::require_stage_of(stages, beat.stage, "stage");  // rolls the update back
    }
    insert_log_lines(tx, changes, job_id, beat.log, now_ms);
    changes.push_back(
        job_change(job_id, beaten[0][2].as<std::string>(), proto::JobState::kRunning));
    touch_worker_of(tx, job_id, now_ms);
    return reply;
  });
}

proto::Artifact PgStore::add_artifact(const std::string& job_id,
                                      const proto::ArtifactRegistration& registration) {
  rules::require_artifact_name(registration.name);
  if (!proto::is_sha256_hex(registration.blob))
    throw Invalid("blob: expected 64 lowercase hex digits (SHA-256), got '" + registration.blob +
                  "'");
  return write([&](PgTx& tx, Changes&) {
    proto::Job job;
    job.id = job_id;
    job.stages = lock_leased_job(tx, job_id, registration.lease_id);
    rules::require_stage_of(job, registration.stage, "stage");
    const auto size = pg_find_blob_size(tx, registration.blob);
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
    tx.exec("DELETE FROM artifacts WHERE job_id = $1 AND stage = $2 AND name = $3", job_id,
            artifact.stage, artifact.name);
    const pqxx::result inserted = tx.exec(
        "INSERT INTO artifacts (id, job_id, stage, name, sha256, size, created_at_ms) "
        "VALUES ($1, $2, $3, $4, $5, $6, $7) "
        "RETURNING (SELECT project FROM jobs WHERE id = $2)",
        artifact.id, job_id, artifact.stage, artifact.name, artifact.sha256, artifact.size,
        artifact.created_at_ms);
    artifact.project = inserted[0][0].as<std::string>();
    pg_note_blob_ref(tx, artifact.project, artifact.sha256);
    return artifact;
  });
}

void PgStore::complete_stage(const std::string& job_id, const std::string& stage,
                             const proto::StageCompletion& completion) {
  if (!std::isfinite(completion.seconds) || completion.seconds < 0)
    throw Invalid("seconds: expected a finite duration >= 0");
  write([&](PgTx& tx, Changes& changes) {
    proto::Job job;
    job.id = job_id;
    job.stages = lock_leased_job(tx, job_id, completion.lease_id);
    rules::require_stage_of(job, stage, "stage");
    tx.exec(
        "INSERT INTO stage_outputs (job_id, stage, report, seconds, completed_at_ms) "
        "VALUES ($1, $2, $3, $4, $5) ON CONFLICT (job_id, stage) DO UPDATE SET "
        "report = excluded.report, seconds = excluded.seconds, "
        "completed_at_ms = excluded.completed_at_ms",
        job_id, stage, completion.report.dump(), completion.seconds, clock_());
    note_job(tx, changes, job_id);
  });
}

proto::Job PgStore::finish_job(const std::string& job_id, const proto::JobFinish& finish,
                               bool succeeded) {
  const int64_t now_ms = clock_();
  const std::string state = succeeded ? "succeeded" : "failed";
  // One statement, committed alone: the fenced update, the worker freed, the job returned.
  static const std::string sql =
      std::string(
          "WITH finished AS ("
          "  UPDATE jobs SET state = $3, error = $4, finished_at_ms = $5, stage = '',"
          "    progress = CASE WHEN $3 = 'succeeded' THEN 1 ELSE progress END,"
          "    lease_id = NULL, lease_expires_at_ms = NULL"
          "  WHERE id = $1 AND lease_id = $2 AND state = 'running' RETURNING *),"
          "freed AS ("
          "  UPDATE workers SET last_seen_ms = $5, job_id = ''"
          "  WHERE id = (SELECT worker FROM finished) AND job_id = $1) "
          "SELECT ") +
      kPgJobColumns + " FROM finished j JOIN missions m ON m.id = j.mission_id";
  Changes changes;
  const proto::Job job = pool_.autocommit([&](PgTx& tx) {
    const pqxx::result rows = tx.exec(sql, job_id, finish.lease_id, state,
                                      without_nul(rules::finish_error(finish, succeeded)), now_ms);
    if (rows.empty()) fence_failure(tx, job_id, finish.lease_id);
    return pg_read_job(rows[0], 0);
  });
  changes.push_back(job_change(job.id, job.project, job.state));
  committed(changes);
  return job;
}

void PgStore::note_worker(PgTx& tx, const std::string& worker, const std::string& job_id,
                          int64_t now_ms) {
  if (worker.empty()) return;
  tx.exec(
      "INSERT INTO workers (id, job_id, last_seen_ms) VALUES ($1, $2, $3) "
      "ON CONFLICT (id) DO UPDATE SET job_id = excluded.job_id, "
      "last_seen_ms = excluded.last_seen_ms",
      worker, job_id, now_ms);
}

void PgStore::touch_worker_of(PgTx& tx, const std::string& job_id, int64_t now_ms) {
  tx.exec(
      "UPDATE workers SET last_seen_ms = $2, job_id = $1 "
      "WHERE id = (SELECT worker FROM jobs WHERE id = $1)",
      job_id, now_ms);
}

void PgStore::release_worker_of(PgTx& tx, const std::string& job_id, int64_t now_ms) {
  tx.exec(
      "UPDATE workers SET last_seen_ms = $2, job_id = '' "
      "WHERE id = (SELECT worker FROM jobs WHERE id = $1) AND job_id = $1",
      job_id, now_ms);
}

// --- artifacts and logs ---

std::vector<proto::Artifact> PgStore::list_artifacts(const std::string& job_id) {
  return read([&](PgTx& tx) {
    if (tx.exec("SELECT 1 FROM jobs WHERE id = $1", job_id).empty())
      throw rules::job_not_found(job_id);
    return pg_job_artifacts(tx, job_id);
  });
}

proto::Artifact PgStore::get_artifact(const std::string& artifact_id) {
  auto artifact = read([&](PgTx& tx) { return pg_find_artifact(tx, artifact_id); });
  if (!artifact) throw NotFound("artifact " + artifact_id + " not found");
  return *artifact;
}

void PgStore::insert_log_lines(PgTx& tx, Changes& changes, const std::string& job_id,
                               const std::vector<std::string>& lines, int64_t now_ms) {
  if (lines.empty()) return;
  const int64_t count = static_cast<int64_t>(lines.size());
  const pqxx::result next = tx.exec(
      "UPDATE jobs SET log_next = log_next + $2 WHERE id = $1 RETURNING log_next - $2, project",
      job_id, count);
  if (next.empty()) throw rules::job_not_found(job_id);
  std::vector<std::string> texts;
  texts.reserve(lines.size());
  for (const std::string& line : lines) texts.push_back(without_nul(line));
  tx.exec(
      "INSERT INTO job_logs (job_id, seq, t_ms, text) "
      "SELECT $1, $2 + l.ord - 1, $3, l.text FROM unnest($4::text[]) WITH ORDINALITY "
      "AS l(text, ord)",
      job_id, next[0][0].as<int64_t>(), now_ms, pg_text_array(texts));
  Change change;
  change.kind = Change::Kind::kLog;
  change.job_id = job_id;
  change.project = next[0][1].as<std::string>();
  changes.push_back(std::move(change));
}

void PgStore::append_log(const std::string& job_id, const std::vector<std::string>& lines) {
  write([&](PgTx& tx, Changes& changes) {
    if (tx.exec("SELECT 1 FROM jobs WHERE id = $1", job_id).empty())
      throw rules::job_not_found(job_id);
    insert_log_lines(tx, changes, job_id, lines, clock_());
  });
}

proto::LogPage PgStore::read_log(const std::string& job_id, int64_t from, int limit) {
  if (from < 0) throw Invalid("from: expected >= 0, got " + std::to_string(from));
  rules::require_list_limit(limit);
  return read([&](PgTx& tx) {
    if (tx.exec("SELECT 1 FROM jobs WHERE id = $1", job_id).empty())
      throw rules::job_not_found(job_id);
    proto::LogPage page;
    page.next = from;
    const pqxx::result rows = tx.exec(
        "SELECT seq, t_ms, text FROM job_logs WHERE job_id = $1 AND seq >= $2 "
        "ORDER BY seq LIMIT $3",
        job_id, from, limit);
    for (const auto& row : rows) {
      page.lines.push_back({row[0].as<int64_t>(), row[1].as<int64_t>(), row[2].as<std::string>()});
      page.next = page.lines.back().seq + 1;
    }
    return page;
  });
}

}  // namespace keel::storage
