// The SQLite implementation of Store. Callers use open_sqlite_store() from store.h; this
// header is for the two .cc files that implement it.
//
// Concurrency: SQLite admits one writer at a time, so all writes go through one connection
// behind `write_mutex_` (BEGIN IMMEDIATE ... COMMIT, synchronous=FULL). Reads use a small
// pool of read-only connections: in WAL mode they see the last committed state without
// waiting for the writer, so GET /v1/jobs/{id} on many threads never queues behind an
// fsync, and each connection caches its prepared statements. Upload chunks are written and
// fsynced outside the database lock, serialized per upload by a striped mutex, so a large
// chunk does not stall other requests.
#pragma once

#include <array>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "storage/blob_store.h"
#include "storage/change_hub.h"
#include "storage/connection_pool.h"
#include "storage/sqlite_db.h"
#include "storage/store.h"
#include "storage/upload_area.h"

namespace keel::storage {

class SqliteStore : public Store {
 public:
  SqliteStore(const std::filesystem::path& data_dir, Clock clock);
  ~SqliteStore() override;

  proto::Upload create_upload(const proto::UploadRequest& request) override;
  proto::Upload get_upload(const std::string& upload_id) override;
  proto::Upload append_upload(const std::string& upload_id, int64_t offset, const char* data,
                              size_t size) override;
  std::string complete_upload(const std::string& upload_id, const std::string& sha256) override;
  void delete_upload(const std::string& upload_id) override;

  bool has_blob(const std::string& sha256) override;
  int64_t blob_size(const std::string& sha256) override;
  std::filesystem::path blob_path(const std::string& sha256) override;
  std::string put_blob(const std::string& bytes) override;

  proto::Mission create_mission(const proto::MissionRequest& request) override;
  proto::Mission get_mission(const std::string& mission_id) override;
  std::vector<proto::Mission> list_missions(const std::string& name_prefix,
                                            const std::string& project) override;

  proto::Job create_job(const proto::JobRequest& request, const std::string& idempotency_key,
                        bool* created) override;
  proto::Job get_job(const std::string& job_id) override;
  std::vector<proto::Job> list_jobs(const JobFilter& filter) override;
  proto::Job cancel_job(const std::string& job_id) override;
  proto::Job retry_job(const std::string& job_id) override;

  proto::Batch create_batch(const proto::ReprocessRequest& request) override;
  proto::Batch get_batch(const std::string& batch_id) override;

  std::optional<proto::Lease> lease_job(const proto::LeaseRequest& request) override;
  proto::Job release_job(const std::string& job_id, const std::string& lease_id) override;
  int requeue_expired_leases() override;
  proto::HeartbeatReply heartbeat(const std::string& job_id, const proto::Heartbeat& beat) override;
  proto::Artifact add_artifact(const std::string& job_id,
                               const proto::ArtifactRegistration& registration) override;
  void complete_stage(const std::string& job_id, const std::string& stage,
                      const proto::StageCompletion& completion) override;
  proto::Job finish_job(const std::string& job_id, const proto::JobFinish& finish,
                        bool succeeded) override;

  std::vector<proto::Artifact> list_artifacts(const std::string& job_id) override;
  proto::Artifact get_artifact(const std::string& artifact_id) override;
  void append_log(const std::string& job_id, const std::vector<std::string>& lines) override;
  proto::LogPage read_log(const std::string& job_id, int64_t from, int limit) override;

  proto::TokenInfo add_token(const std::string& token, const TokenSpec& spec) override;
  std::optional<proto::TokenInfo> check_token(const std::string& token) override;
  std::vector<proto::TokenInfo> list_tokens() override;
  proto::TokenInfo revoke_token(const std::string& token_id) override;
  int64_t token_count() override;

  std::vector<proto::Project> list_projects() override;
  proto::Project ensure_project(const std::string& name) override;
  proto::Project set_project_quota(const std::string& name, int64_t quota_bytes) override;
  int64_t project_usage(const std::string& name) override;
  bool project_has_blob(const std::string& name, const std::string& sha256) override;

  std::unique_ptr<Subscription> subscribe(ChangeListener listener) override;
  proto::QueueSummary queue_summary() override;

  Metrics metrics() override;

 private:
  // Runs `work(db)` in one write transaction on the writer connection and commits; then,
  // outside the lock, publishes the changes `work` noted (note_job / note_log).
  template <typename Work>
  auto write(Work work) {
    try {
      return write_unchecked(work);
    } catch (const SqliteError& e) {
      // A full disk rolls the transaction back: tell the caller in its own terms.
      if (e.disk_full()) throw StorageFull(std::string("no space left for the database: ") + e.what());
      throw;
    }
  }
  template <typename Work>
  auto write_unchecked(Work work) {
    std::vector<Change> changes;
    if constexpr (std::is_void_v<decltype(work(*writer_))>) {
      {
        std::lock_guard<std::mutex> lock(write_mutex_);
        pending_changes_.clear();
        Transaction transaction(*writer_);
        work(*writer_);
        transaction.commit();
        changes.swap(pending_changes_);
      }
      changes_.publish(changes);
    } else {
      auto result = [&] {
        std::lock_guard<std::mutex> lock(write_mutex_);
        pending_changes_.clear();
        Transaction transaction(*writer_);
        auto value = work(*writer_);
        transaction.commit();
        changes.swap(pending_changes_);
        return value;
      }();
      changes_.publish(changes);
      return result;
    }
  }
  // Inside write(): the job's row changed (state, stage, progress, ...) / got log lines.
  void note_job(Database& db, const std::string& job_id);
  void note_log(Database& db, const std::string& job_id);
  // Inside write(): the worker called the worker protocol now, holding `job_id` ("" = none).
  void note_worker(Database& db, const std::string& worker, const std::string& job_id,
                   int64_t now_ms);
  // The job's worker was heard from now (heartbeat) / no longer holds the job.
  void touch_worker_of(Database& db, const std::string& job_id, int64_t now_ms);
  void release_worker_of(Database& db, const std::string& job_id, int64_t now_ms);
  // Runs `work(db)` on a pooled reader connection (each statement sees committed data).
  template <typename Work>
  auto read(Work work) {
    ConnectionPool::Handle db = readers_.acquire();
    return work(*db);
  }

  std::mutex& upload_lock(const std::string& upload_id);
  // Cuts uncommitted bytes off every part file and removes part files with no upload.
  void recover_uploads();
  // Deletes the upload's row and then its part file (after a failed completion).
  void discard_upload(const std::string& upload_id);

  // Lease checks shared by the worker calls (inside a write transaction). Throws NotFound,
  // LeaseLost, or Conflict when the job is not running (canceled, finished).
  proto::Job require_running_lease(Database& db, const std::string& job_id,
                                   const std::string& lease_id);
  // Requeues (or fails, at the third expiry) running jobs whose lease has expired.
  int expire_leases(Database& db, int64_t now_ms);
  // The project a request names ("" = default), created when new; Invalid for a bad name.
  std::string project_of_request(Database& db, const std::string& project);
  // Inside write(): the project references the blob (project_usage, project_has_blob).
  void note_blob_ref(Database& db, const std::string& project, const std::string& sha256);
  void insert_log_lines(Database& db, const std::string& job_id,
                        const std::vector<std::string>& lines, int64_t now_ms);

  std::filesystem::path data_dir_;
  int lock_fd_ = -1;  // flock on <data_dir>/keel.lock while this store did the recovery
  Clock clock_;
  BlobStore blobs_;
  UploadArea uploads_;
  std::mutex write_mutex_;
  std::unique_ptr<Database> writer_;
  ConnectionPool readers_;
  std::array<std::mutex, 64> upload_locks_;
  std::vector<Change> pending_changes_;  // guarded by write_mutex_
  ChangeHub changes_;
};

}  // namespace keel::storage
