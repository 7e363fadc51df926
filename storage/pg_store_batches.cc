// PgStore: reprocess batches (one transaction and a few statements for any number of
// missions) and the queue summary behind GET /v1/queue.
#include <map>
#include <unordered_map>
#include <unordered_set>

#include "storage/ids.h"
#include "storage/pg_queries.h"
#include "storage/pg_store.h"
#include "storage/store_rules.h"

namespace keel::storage {

namespace {

// The missions a batch runs on, oldest first (or as listed), all of `project`.
std::vector<std::string> batch_missions(PgTx& tx, const proto::ReprocessRequest& request,
                                        const std::string& project) {
  std::vector<std::string> ids;
  if (!request.mission_ids.empty()) {
    std::unordered_map<std::string, std::string> project_of;
    const pqxx::result rows = tx.exec("SELECT id, project FROM missions WHERE id = ANY($1::text[])",
                                      pg_text_array(request.mission_ids));
    for (const auto& row : rows) project_of[row[0].as<std::string>()] = row[1].as<std::string>();
    std::unordered_set<std::string> seen;
    for (size_t i = 0; i < request.mission_ids.size(); ++i) {
      const std::string& id = request.mission_ids[i];
      auto found = project_of.find(id);
      if (found == project_of.end() || found->second != project)
        throw NotFound("mission_ids[" + std::to_string(i) + "]: mission " + id + " not found");
      if (seen.insert(id).second) ids.push_back(id);
    }
    return ids;
  }
  const pqxx::result rows =
      tx.exec("SELECT id FROM missions WHERE project = $1 AND starts_with(name, $2) ORDER BY seq",
              project, request.name_prefix);
  ids.reserve(rows.size());
  for (const auto& row : rows) ids.push_back(row[0].as<std::string>());
  return ids;
}

// The job each reprocess job reprocesses, by mission: the mission's latest succeeded job that
// is not a comparison job (missions without one are absent). One statement for the batch.
std::map<std::string, std::string> earlier_jobs(PgTx& tx, const std::vector<std::string>& missions,
                                                const std::string& project) {
  const pqxx::result rows = tx.exec(
      "SELECT DISTINCT ON (mission_id) mission_id, id FROM jobs "
      "WHERE mission_id = ANY($1::text[]) AND project = $2 AND state = 'succeeded' "
      "AND stages <> $3 ORDER BY mission_id, finished_at_ms DESC, seq DESC",
      pg_text_array(missions), project, std::string(rules::kCompareOnlyStages));
  std::map<std::string, std::string> out;
  for (const auto& row : rows) out[row[0].as<std::string>()] = row[1].as<std::string>();
  return out;
}

}  // namespace

proto::Batch PgStore::create_batch(const proto::ReprocessRequest& request) {
  if (!request.mission_ids.empty() && !request.name_prefix.empty())
    throw Invalid("give either mission_ids or name_prefix, not both");
  rules::require_pipeline(request.stages, request.options);
  const std::string stages = nlohmann::json(request.stages).dump();
  const std::string options = request.options.dump();
  return write([&](PgTx& tx, Changes& changes) {
    proto::Batch batch;
    batch.id = new_id(kBatchPrefix);
    batch.project = project_of_request(tx, request.project);
    batch.created_at_ms = clock_();
    const std::vector<std::string> missions = batch_missions(tx, request, batch.project);
    std::vector<std::string> job_ids;
    job_ids.reserve(missions.size());
    for (size_t i = 0; i < missions.size(); ++i) job_ids.push_back(new_id(kJobPrefix));
    std::vector<std::string> job_stages(missions.size(), stages), job_options(missions.size(), options);
    if (request.compare) {
      const std::map<std::string, std::string> earlier = earlier_jobs(tx, missions, batch.project);
      for (size_t i = 0; i < missions.size(); ++i) {
        const auto found = earlier.find(missions[i]);
        if (found == earlier.end()) continue;
        const rules::BatchJobPipeline pipeline = rules::with_compare(request.stages, request.options, found->second);
        job_stages[i] = pipeline.stages;
        job_options[i] = pipeline.options;
        ++batch.compared;
      }
    }
    // One INSERT for every job, in the missions' order (their seq follows it).
    tx.exec(
        "INSERT INTO jobs (id, mission_id, state, stages, options, created_at_ms, project, "
        "batch_id) SELECT j.id, j.mission, 'queued', j.stages, j.options, $5, $6, $7 "
        "FROM unnest($1::text[], $2::text[], $3::text[], $4::text[]) WITH ORDINALITY "
        "AS j(id, mission, stages, options, ord) ORDER BY j.ord",
        pg_text_array(job_ids), pg_text_array(missions), pg_text_array(job_stages),
        pg_text_array(job_options), batch.created_at_ms, batch.project, batch.id);
    tx.exec("INSERT INTO batches (id, project, jobs, created_at_ms) VALUES ($1, $2, $3, $4)",
            batch.id, batch.project, static_cast<int64_t>(missions.size()), batch.created_at_ms);
    batch.jobs = static_cast<int64_t>(missions.size());
    batch.jobs_by_state = rules::zero_counts();
    batch.jobs_by_state["queued"] = batch.jobs;
    if (batch.jobs > 0) {
      // One wake-up for the whole batch: waiting workers lease from the queue in order.
      Change change;
      change.project = batch.project;
      change.state = proto::JobState::kQueued;
      changes.push_back(change);
    }
    return batch;
  });
}

proto::Batch PgStore::get_batch(const std::string& batch_id) {
  return read([&](PgTx& tx) {
    proto::Batch batch;
    const pqxx::result rows =
        tx.exec("SELECT id, project, jobs, created_at_ms FROM batches WHERE id = $1", batch_id);
    if (rows.empty()) throw NotFound("batch " + batch_id + " not found");
    batch.id = rows[0][0].as<std::string>();
    batch.project = rows[0][1].as<std::string>();
    batch.jobs = rows[0][2].as<int64_t>();
    batch.created_at_ms = rows[0][3].as<int64_t>();
    batch.jobs_by_state = rules::zero_counts();
    // One statement: counts by state and the finished jobs' mean time, from one snapshot
    // (the state column is NULL on the timing row).
    const pqxx::result counts = tx.exec(
        "SELECT state, COUNT(*), 0::float8 FROM jobs WHERE batch_id = $1 GROUP BY state "
        "UNION ALL SELECT NULL, COUNT(*), COALESCE(AVG(finished_at_ms - started_at_ms), 0) "
        "FROM jobs WHERE batch_id = $1 AND state IN ('succeeded', 'failed') "
        "AND started_at_ms > 0",
        batch_id);
    for (const auto& row : counts) {
      if (row[0].is_null()) {
        batch.finished_jobs_timed = row[1].as<int64_t>();
        batch.mean_job_seconds = row[2].as<double>() / 1000.0;
      } else {
        batch.jobs_by_state[row[0].as<std::string>()] = row[1].as<int64_t>();
      }
    }
    return batch;
  });
}

proto::QueueSummary PgStore::queue_summary() {
  const int64_t now_ms = clock_();
  return read([&](PgTx& tx) {
    proto::QueueSummary summary;
    summary.jobs_by_state = rules::zero_counts();
    for (const auto& row : tx.exec("SELECT state, COUNT(*) FROM jobs GROUP BY state"))
      summary.jobs_by_state[row[0].as<std::string>()] = row[1].as<int64_t>();
    const pqxx::result workers =
        tx.exec("SELECT id, job_id, last_seen_ms FROM workers WHERE last_seen_ms >= $1 ORDER BY id",
                now_ms - rules::kHourMs);
    for (const auto& row : workers) {
      proto::WorkerInfo worker;
      worker.id = row[0].as<std::string>();
      worker.job_id = row[1].as<std::string>();
      worker.last_seen_ms = row[2].as<int64_t>();
      worker.alive = now_ms - worker.last_seen_ms <= rules::kWorkerAliveMs;
      summary.workers_alive += worker.alive ? 1 : 0;
      summary.workers.push_back(std::move(worker));
    }
    const pqxx::row hour = tx.exec(
        "SELECT COUNT(*), COUNT(*) FILTER (WHERE state = 'failed'), "
        "COALESCE(AVG(finished_at_ms - started_at_ms) FILTER (WHERE started_at_ms > 0), 0) "
        "FROM jobs WHERE finished_at_ms >= $1 AND state IN ('succeeded', 'failed')",
        now_ms - rules::kHourMs)[0];
    summary.finished_last_hour = hour[0].as<int64_t>();
    summary.failed_last_hour = hour[1].as<int64_t>();
    summary.mean_job_seconds_last_hour = hour[2].as<double>() / 1000.0;
    return summary;
  });
}

}  // namespace keel::storage
