// The Store's rules, written once above the SQL interface of storage/sql.h: leases,
// heartbeats, expiry and requeue, fencing by lease, release, stage completion, finish,
// artifacts, uploads, batches, idempotency, tokens and projects. SQLite (open_sqlite_store,
// sqlite_store.cc) and PostgreSQL (PgStore, pg_store.h) run them on their own Sql; what
// differs between the two is only there.
//
// - Fencing: a worker call changes the job only in a statement (or under a row lock) that
//   names the job, the lease and state 'running', so a stale worker's call changes nothing;
//   only then is the reason read for the error (NotFound, LeaseLost, Conflict).
// - Leases take the oldest queued job ({skip_locked}: concurrent leases on any replica take
//   the next one instead of waiting), after requeueing expired leases; any replica may
//   requeue them at any time.
// - Uploads: the committed offset is in the database, the part file in the (shared) folder.
//   A chunk is written and fsynced before its offset commits, under the upload's lock (this
//   process's, and for PostgreSQL the row's across replicas), so a resume is byte-exact.
// - Changes committed by a write reach this store's listeners after the commit (and, with
//   PostgreSQL, other replicas' changes too).
#pragma once

#include <array>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "storage/blob_store.h"
#include "storage/change_hub.h"
#include "storage/sql.h"
#include "storage/store.h"
#include "storage/upload_area.h"

namespace keel::storage {

// The store's folder: blobs/, tmp/ and uploads/.
struct StoreFiles {
  std::filesystem::path dir;
  // Cut uncommitted upload bytes and remove left-over files when opening. False for a
  // second process on a SQLite folder whose first one is alive (it may be writing them).
  bool recover = true;
  // Temp files younger than this may be another replica's blob being written (0: every
  // temp file is left over).
  int64_t stale_file_age_s = 0;
};

class SqlStore : public Store {
 public:
  // `sql` must hold Keel's schema (migrated) already.
  SqlStore(std::unique_ptr<Sql> sql, const StoreFiles& files, Clock clock);

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
  template <typename Work>
  auto write(Work&& work, Sql::Mode mode = Sql::Mode::kWrite) {
    return sql_->run(mode, std::forward<Work>(work));
  }
  template <typename Work>
  auto read(Work&& work) {
    return sql_->run(Sql::Mode::kRead, std::forward<Work>(work));
  }

  // The project a request names ("" = default), created when new; Invalid for a bad name.
  std::string project_of_request(SqlTx& tx, const std::string& project);

  std::mutex& upload_lock(const std::string& upload_id);
  // Cuts uncommitted bytes off part files no one is writing, and removes left-over files.
  void recover_uploads(int64_t stale_file_age_s);
  void discard_upload(const std::string& upload_id);

  ChangeHub changes_;  // outlives sql_, which may deliver changes from a thread of its own
  Clock clock_;
  BlobStore blobs_;
  UploadArea uploads_;
  std::array<std::mutex, 64> upload_locks_;
  std::unique_ptr<Sql> sql_;
};

}  // namespace keel::storage
