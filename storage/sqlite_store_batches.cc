// SqliteStore: reprocess batches (one transaction for any number of missions) and the queue
// summary behind GET /v1/queue.
#include <algorithm>
#include <unordered_set>

#include "storage/ids.h"
#include "storage/sqlite_queries.h"
#include "storage/sqlite_store.h"
#include "storage/store_rules.h"

namespace keel::storage {

namespace {

using namespace rules;

// The missions a batch runs on, oldest first, all of `project`.
std::vector<std::string> batch_missions(Database& db, const proto::ReprocessRequest& request,
                                        const std::string& project) {
  std::vector<std::string> ids;
  if (!request.mission_ids.empty()) {
    std::unordered_set<std::string> seen;
    auto statement = db.cached("SELECT project FROM missions WHERE id = ?1");
    for (size_t i = 0; i < request.mission_ids.size(); ++i) {
      const std::string& id = request.mission_ids[i];
      statement->reset();
      statement->bind_text(1, id);
      if (!statement->step() || statement->column_text(0) != project)
        throw NotFound("mission_ids[" + std::to_string(i) + "]: mission " + id + " not found");
      if (seen.insert(id).second) ids.push_back(id);
    }
    return ids;
  }
  auto statement = db.cached(
      "SELECT id FROM missions WHERE project = ?1 AND (?2 = '' OR instr(name, ?2) = 1) "
      "ORDER BY seq");
  statement->bind_text(1, project).bind_text(2, request.name_prefix);
  while (statement->step()) ids.push_back(statement->column_text(0));
  return ids;
}

// The job a reprocess job reprocesses: its mission's latest succeeded job that is not a
// comparison job, or "" when there is none.
std::string earlier_job(Database& db, const std::string& mission_id, const std::string& project) {
  auto statement = db.cached(
      "SELECT id FROM jobs WHERE mission_id = ?1 AND project = ?2 AND state = 'succeeded' "
      "AND stages <> ?3 ORDER BY finished_at_ms DESC, seq DESC LIMIT 1");
  statement->bind_text(1, mission_id).bind_text(2, project).bind_text(3, kCompareOnlyStages);
  return statement->step() ? statement->column_text(0) : "";
}

}  // namespace

proto::Batch SqliteStore::create_batch(const proto::ReprocessRequest& request) {
  if (!request.mission_ids.empty() && !request.name_prefix.empty())
    throw Invalid("give either mission_ids or name_prefix, not both");
  require_pipeline(request.stages, request.options);
  const std::string stages = nlohmann::json(request.stages).dump();
  const std::string options = request.options.dump();
  return write([&](Database& db) {
    proto::Batch batch;
    batch.id = new_id(kBatchPrefix);
    batch.project = project_of_request(db, request.project);
    batch.created_at_ms = clock_();
    const std::vector<std::string> missions = batch_missions(db, request, batch.project);
    auto insert = db.cached(
        "INSERT INTO jobs (id, mission_id, state, stages, options, created_at_ms, project, "
        "batch_id) VALUES (?1, ?2, 'queued', ?3, ?4, ?5, ?6, ?7)");
    for (const std::string& mission_id : missions) {
      const std::string job_id = new_id(kJobPrefix);
      BatchJobPipeline pipeline{stages, options};
      if (request.compare) {
        const std::string earlier = earlier_job(db, mission_id, batch.project);
        if (!earlier.empty()) {
          pipeline = with_compare(request.stages, request.options, earlier);
          ++batch.compared;
        }
      }
      insert->reset();
      insert->bind_text(1, job_id)
          .bind_text(2, mission_id)
          .bind_text(3, pipeline.stages)
          .bind_text(4, pipeline.options)
          .bind_int64(5, batch.created_at_ms)
          .bind_text(6, batch.project)
          .bind_text(7, batch.id)
          .run();
    }
    auto record =
        db.cached("INSERT INTO batches (id, project, jobs, created_at_ms) VALUES (?1, ?2, ?3, ?4)");
    record->bind_text(1, batch.id)
        .bind_text(2, batch.project)
        .bind_int64(3, static_cast<int64_t>(missions.size()))
        .bind_int64(4, batch.created_at_ms)
        .run();
    batch.jobs = static_cast<int64_t>(missions.size());
    batch.jobs_by_state = zero_counts();
    batch.jobs_by_state["queued"] = batch.jobs;
    if (batch.jobs > 0) {
      // One wake-up for the whole batch: waiting workers lease from the queue in order.
      Change change;
      change.job_id = "";
      change.project = batch.project;
      change.state = proto::JobState::kQueued;
      pending_changes_.push_back(change);
    }
    return batch;
  });
}

proto::Batch SqliteStore::get_batch(const std::string& batch_id) {
  return read([&](Database& db) {
    Transaction snapshot(db, Transaction::Mode::kDeferred);
    proto::Batch batch;
    {
      auto statement =
          db.cached("SELECT id, project, jobs, created_at_ms FROM batches WHERE id = ?1");
      statement->bind_text(1, batch_id);
      if (!statement->step()) throw NotFound("batch " + batch_id + " not found");
      batch.id = statement->column_text(0);
      batch.project = statement->column_text(1);
      batch.jobs = statement->column_int64(2);
      batch.created_at_ms = statement->column_int64(3);
    }
    batch.jobs_by_state = zero_counts();
    {
      auto statement =
          db.cached("SELECT state, COUNT(*) FROM jobs WHERE batch_id = ?1 GROUP BY state");
      statement->bind_text(1, batch_id);
      while (statement->step())
        batch.jobs_by_state[statement->column_text(0)] = statement->column_int64(1);
    }
    {
      auto statement = db.cached(
          "SELECT COUNT(*), COALESCE(AVG(finished_at_ms - started_at_ms), 0) FROM jobs "
          "WHERE batch_id = ?1 AND state IN ('succeeded', 'failed') AND started_at_ms > 0");
      statement->bind_text(1, batch_id);
      statement->step();
      batch.finished_jobs_timed = statement->column_int64(0);
      batch.mean_job_seconds = statement->column_double(1) / 1000.0;
    }
    snapshot.commit();
    return batch;
  });
}

proto::QueueSummary SqliteStore::queue_summary() {
  const int64_t now_ms = clock_();
  return read([&](Database& db) {
    Transaction snapshot(db, Transaction::Mode::kDeferred);
    proto::QueueSummary summary;
    summary.jobs_by_state = zero_counts();
    {
      auto statement = db.cached("SELECT state, COUNT(*) FROM jobs GROUP BY state");
      while (statement->step())
        summary.jobs_by_state[statement->column_text(0)] = statement->column_int64(1);
    }
    {
      auto statement = db.cached(
          "SELECT id, job_id, last_seen_ms FROM workers WHERE last_seen_ms >= ?1 ORDER BY id");
      statement->bind_int64(1, now_ms - kHourMs);
      while (statement->step()) {
        proto::WorkerInfo worker;
        worker.id = statement->column_text(0);
        worker.job_id = statement->column_text(1);
        worker.last_seen_ms = statement->column_int64(2);
        worker.alive = now_ms - worker.last_seen_ms <= kWorkerAliveMs;
        summary.workers_alive += worker.alive ? 1 : 0;
        summary.workers.push_back(std::move(worker));
      }
    }
    {
      auto statement = db.cached(
          "SELECT COUNT(*), COALESCE(SUM(state = 'failed'), 0), "
          "COALESCE(AVG(CASE WHEN started_at_ms > 0 THEN finished_at_ms - started_at_ms END), 0) "
          "FROM jobs WHERE finished_at_ms >= ?1 AND state IN ('succeeded', 'failed')");
      statement->bind_int64(1, now_ms - kHourMs);
      statement->step();
      summary.finished_last_hour = statement->column_int64(0);
      summary.failed_last_hour = statement->column_int64(1);
      summary.mean_job_seconds_last_hour = statement->column_double(2) / 1000.0;
    }
    snapshot.commit();
    return summary;
  });
}

}  // namespace keel::storage
