// The PostgreSQL implementation of Store, for several keel-server replicas on one database
// and one shared blob folder. Callers use open_store() (storage/open_store.h); this header is
// for the .cc files that implement it. Semantics are SqliteStore's (one typed test suite
// runs against both); what differs is how they hold under several replicas:
//
// - Queue: a lease takes the oldest runnable job with one statement (a MATERIALIZED CTE
//   with FOR UPDATE SKIP LOCKED feeding the UPDATE), so concurrent leases on any replica
//   never wait for each other or take the same job. Every worker call is fenced by the
//   lease: its UPDATE names the job, the lease id and state 'running'. Expired leases are
//   requeued by one statement any replica may run at any time (requeue_expired_leases).
// - Idempotency-Key is UNIQUE in the database: replicas agree on the first job.
// - Change feed: this replica's listeners get a transaction's changes at once after its
//   commit (never for a rollback); other replicas hear them through pg_notify, sent after
//   the commit in batches (PgNotifier says why), on their LISTEN connection (PgListener).
// - Uploads: the committed offset is in the database and the part file in the shared
//   folder; an append holds the upload's row lock while it cuts, writes and fsyncs the
//   chunk, so two replicas never write one upload at once and any replica can continue it.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "storage/blob_store.h"
#include "storage/change_hub.h"
#include "storage/pg_connection.h"
#include "storage/pg_listener.h"
#include "storage/pg_notifier.h"
#include "storage/store.h"
#include "storage/upload_area.h"

namespace keel::storage {

struct PgStoreOptions {
  std::string database_url;        // postgresql://...
  std::filesystem::path blob_dir;  // shared: blobs/, tmp/, uploads/
  size_t max_connections = 32;     // per replica
  int connect_timeout_s = 5;       // an unreachable host fails after this long
  // Temp and orphan part files younger than this may belong to another replica's write in
  // progress; older ones are left by a crash and removed at open.
  int64_t stale_file_age_s = 3600;
  bool listen = true;  // tell other replicas of changes and hear theirs (NOTIFY/LISTEN)
};

class PgStore : public Store {
 public:
  PgStore(const PgStoreOptions& options, Clock clock);
  ~PgStore() override;

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
  using Changes = std::vector<Change>;

  // Runs `work(tx, changes)` in one transaction; after the commit the changes it noted are
  // published to this replica's listeners and queued for the others. A retried transaction
  // starts with no changes noted.
  template <typename Work>
  auto write(Work work) {
    Changes changes;
    if constexpr (std::is_void_v<decltype(work(std::declval<PgTx&>(), changes))>) {
      pool_.transact([&](PgTx& tx) {
        changes.clear();
        work(tx, changes);
      });
      committed(changes);
    } else {
      auto result = pool_.transact([&](PgTx& tx) {
        changes.clear();
        return work(tx, changes);
      });
      committed(changes);
      return result;
    }
  }
  template <typename Work>
  auto read(Work work) {
    return pool_.transact(work);
  }

  void committed(const Changes& changes);
  // Notes the job's change (reads its project and state) / its new log lines.
  void note_job(PgTx& tx, Changes& changes, const std::string& job_id);
  void note_log(PgTx& tx, Changes& changes, const std::string& job_id);
  // The worker called the worker protocol now, holding `job_id` ("" = none).
  void note_worker(PgTx& tx, const std::string& worker, const std::string& job_id, int64_t now_ms);
  void touch_worker_of(PgTx& tx, const std::string& job_id, int64_t now_ms);
  void release_worker_of(PgTx& tx, const std::string& job_id, int64_t now_ms);

  // Lease checks shared by the worker calls: locks the job's row and throws NotFound,
  // LeaseLost, or Conflict when the job is not running (canceled, finished).
  proto::Job require_running_lease(PgTx& tx, const std::string& job_id,
                                   const std::string& lease_id);
  int expire_leases(PgTx& tx, Changes& changes, int64_t now_ms);
  std::string project_of_request(PgTx& tx, const std::string& project);
  // Appends lines to the job's log (the job's row must be locked or updated by the caller's
  // transaction: jobs.log_next hands out the numbers).
  void insert_log_lines(PgTx& tx, Changes& changes, const std::string& job_id,
                        const std::vector<std::string>& lines, int64_t now_ms);

  // Cuts uncommitted bytes off part files no replica is writing, and removes stale files.
  void recover_uploads();
  void discard_upload(const std::string& upload_id);

  PgStoreOptions options_;
  Clock clock_;
  BlobStore blobs_;
  UploadArea uploads_;
  PgPool pool_;
  std::string origin_;  // this store's id in its notifications (its own are not re-heard)
  ChangeHub changes_;
  std::unique_ptr<PgNotifier> notifier_;
  std::unique_ptr<PgListener> listener_;
};

}  // namespace keel::storage
