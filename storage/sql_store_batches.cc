// SqlStore: reprocess batches (one transaction for any number of missions) and the queue
// summary behind GET /v1/queue.
#include <map>
#include <unordered_set>

#include "storage/ids.h"
#include "storage/sql_queries.h"
#include "storage/sql_store.h"

namespace keel::storage {

namespace {

// A worker that called the worker protocol this recently is alive (docs/api.md).
constexpr int64_t kWorkerAliveMs = 60'000;
constexpr int64_t kHourMs = 3'600'000;
// The jobs table's text of a comparison job's stages: such a job is never "the job a
// reprocess job reprocesses".
constexpr const char* kCompareOnlyStages = "[\"compare\"]";

// A job's stages and options as the jobs table holds them (JSON text).
struct Pipeline {
  std::string stages, options;
};

// A reprocess job that also compares with the job it reprocesses (ReprocessRequest::compare):
// its stages with `compare` last, and its options with options.compare.job_a = `earlier_job`.
Pipeline with_compare(std::vector<std::string> stages, nlohmann::json options,
                      const std::string& earlier_job) {
  stages.push_back("compare");
  if (!options.is_object()) options = nlohmann::json::object();
  if (!options.contains("compare") || !options["compare"].is_object())
    options["compare"] = nlohmann::json::object();
  options["compare"]["job_a"] = earlier_job;  // job_b: the job itself (compare_stage.h)
  return {nlohmann::json(stages).dump(), options.dump()};
}

// Every job state with a count of 0.
std::map<std::string, int64_t> zero_counts() {
  std::map<std::string, int64_t> counts;
  for (auto state :
       {proto::JobState::kQueued, proto::JobState::kRunning, proto::JobState::kSucceeded,
        proto::JobState::kFailed, proto::JobState::kCanceled})
    counts[proto::to_string(state)] = 0;
  return counts;
}

// The missions a batch runs on, oldest first (or as listed), all of `project`.
std::vector<std::string> batch_missions(SqlTx& tx, const proto::ReprocessRequest& request,
                                        const std::string& project) {
  std::vector<std::string> ids;
  if (!request.mission_ids.empty()) {
    std::unordered_set<std::string> seen;
    for (size_t i = 0; i < request.mission_ids.size(); ++i) {
      const std::string& id = request.mission_ids[i];
      auto row = tx.row("SELECT project FROM missions WHERE id = ?1", {id});
      if (!row || row->text(0) != project)
        throw NotFound("mission_ids[" + std::to_string(i) + "]: mission " + id + " not found");
      if (seen.insert(id).second) ids.push_back(id);
    }
    return ids;
  }
  for (const SqlRow& row : tx.query("SELECT id FROM missions WHERE project = ?1 AND "
                                    "(?2 = '' OR {instr}(name, ?2) = 1) ORDER BY seq",
                                    {project, request.name_prefix}))
    ids.push_back(row.text(0));
  return ids;
}

// The job a reprocess job reprocesses: its mission's latest succeeded job that is not a
// comparison job, or "" when there is none.
std::string earlier_job(SqlTx& tx, const std::string& mission_id, const std::string& project) {
  auto row = tx.row(
      "SELECT id FROM jobs WHERE mission_id = ?1 AND project = ?2 AND state = 'succeeded' "
      "AND stages <> ?3 ORDER BY finished_at_ms DESC, seq DESC LIMIT 1",
      {mission_id, project, std::string(kCompareOnlyStages)});
  return row ? row->text(0) : "";
}

}  // namespace

proto::Batch SqlStore::create_batch(const proto::ReprocessRequest& request) {
  if (!request.mission_ids.empty() && !request.name_prefix.empty())
    throw Invalid("give either mission_ids or name_prefix, not both");
  require_pipeline(request.stages, request.options);
  const Pipeline plain{nlohmann::json(request.stages).dump(), request.options.dump()};
  return write([&](SqlTx& tx) {
    proto::Batch batch;
    batch.id = new_id(kBatchPrefix);
    batch.project = project_of_request(tx, request.project);
    batch.created_at_ms = clock_();
    const std::vector<std::string> missions = batch_missions(tx, request, batch.project);
    // One INSERT of up to kRowsPerInsert jobs at a time (and the rest in halving chunks, so a
    // connection prepares only a few statements): a batch of thousands of missions is a few
    // dozen statements, in the missions' order (their seq follows it).
    constexpr size_t kRowsPerInsert = 128;
    for (size_t first = 0, rows = kRowsPerInsert; first < missions.size(); first += rows) {
      while (rows > missions.size() - first) rows /= 2;
      std::string sql =
          "INSERT INTO jobs (id, mission_id, state, stages, options, created_at_ms, project, "
          "batch_id) VALUES ";
      std::vector<SqlValue> params = {batch.created_at_ms, batch.project, batch.id};
      for (size_t i = first; i < first + rows; ++i) {
        Pipeline pipeline = plain;
        if (request.compare) {
          const std::string earlier = earlier_job(tx, missions[i], batch.project);
          if (!earlier.empty()) {
            pipeline = with_compare(request.stages, request.options, earlier);
            ++batch.compared;
          }
        }
        const size_t at = params.size();
        sql += std::string(i > first ? ", " : "") + "(?" + std::to_string(at + 1) + ", ?" +
               std::to_string(at + 2) + ", 'queued', ?" + std::to_string(at + 3) + ", ?" +
               std::to_string(at + 4) + ", ?1, ?2, ?3)";
        params.insert(params.end(),
                      {new_id(kJobPrefix), missions[i], pipeline.stages, pipeline.options});
      }
      tx.exec(sql, params);
    }
    batch.jobs = static_cast<int64_t>(missions.size());
    tx.exec("INSERT INTO batches (id, project, jobs, created_at_ms) VALUES (?1, ?2, ?3, ?4)",
            {batch.id, batch.project, batch.jobs, batch.created_at_ms});
    batch.jobs_by_state = zero_counts();
    batch.jobs_by_state["queued"] = batch.jobs;
    if (batch.jobs > 0) {
      // One wake-up for the whole batch: waiting workers lease from the queue in order.
      Change change;
      change.project = batch.project;
      change.state = proto::JobState::kQueued;
      tx.changes.push_back(change);
    }
    return batch;
  });
}

proto::Batch SqlStore::get_batch(const std::string& batch_id) {
  return read([&](SqlTx& tx) {
    auto row =
        tx.row("SELECT id, project, jobs, created_at_ms FROM batches WHERE id = ?1", {batch_id});
    if (!row) throw NotFound("batch " + batch_id + " not found");
    proto::Batch batch;
    batch.id = row->text(0);
    batch.project = row->text(1);
    batch.jobs = row->int64(2);
    batch.created_at_ms = row->int64(3);
    batch.jobs_by_state = zero_counts();
    for (const SqlRow& count : tx.query(
             "SELECT state, COUNT(*) FROM jobs WHERE batch_id = ?1 GROUP BY state", {batch_id}))
      batch.jobs_by_state[count.text(0)] = count.int64(1);
    const SqlRow timed = *tx.row(
        "SELECT COUNT(*), COALESCE(AVG(finished_at_ms - started_at_ms), 0) FROM jobs "
        "WHERE batch_id = ?1 AND state IN ('succeeded', 'failed') AND started_at_ms > 0",
        {batch_id});
    batch.finished_jobs_timed = timed.int64(0);
    batch.mean_job_seconds = timed.real(1) / 1000.0;
    return batch;
  });
}

proto::QueueSummary SqlStore::queue_summary() {
  const int64_t now_ms = clock_();
  return read([&](SqlTx& tx) {
    proto::QueueSummary summary;
    summary.jobs_by_state = zero_counts();
    for (const SqlRow& row : tx.query("SELECT state, COUNT(*) FROM jobs GROUP BY state"))
      summary.jobs_by_state[row.text(0)] = row.int64(1);
    for (const SqlRow& row :
         tx.query("SELECT id, job_id, last_seen_ms FROM workers WHERE last_seen_ms >= ?1 "
                  "ORDER BY id",
                  {now_ms - kHourMs})) {
      proto::WorkerInfo worker;
      worker.id = row.text(0);
      worker.job_id = row.text(1);
      worker.last_seen_ms = row.int64(2);
      worker.alive = now_ms - worker.last_seen_ms <= kWorkerAliveMs;
      summary.workers_alive += worker.alive ? 1 : 0;
      summary.workers.push_back(std::move(worker));
    }
    const SqlRow hour = *tx.row(
        "SELECT COUNT(*), COALESCE(SUM(CASE WHEN state = 'failed' THEN 1 ELSE 0 END), 0), "
        "COALESCE(AVG(CASE WHEN started_at_ms > 0 THEN finished_at_ms - started_at_ms END), 0) "
        "FROM jobs WHERE finished_at_ms >= ?1 AND state IN ('succeeded', 'failed')",
        {now_ms - kHourMs});
    summary.finished_last_hour = hour.int64(0);
    summary.failed_last_hour = hour.int64(1);
    summary.mean_job_seconds_last_hour = hour.real(2) / 1000.0;
    return summary;
  });
}

}  // namespace keel::storage
