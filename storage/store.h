// Keel's durable state behind one interface: uploads, blobs, missions, jobs with leases,
// stage outputs, artifacts, job logs, API tokens with roles, projects and reprocess batches.
// The server calls only this interface: SQLite (one machine, the default) and PostgreSQL
// (several replicas) implement it, and one typed test suite runs against both.
//
// Projects: every upload, mission, job (and so artifact and batch) belongs to a project.
// Requests carry it (`project`; "" means kDefaultProject); a job takes its mission's project.
// Reads return the object with its `project` and do NOT check it: the server compares it
// with the token's project and answers 404 for another project's object. Listings take a
// project filter ("" or kAllProjects = every project).
//
// Every method is atomic (one transaction) and thread-safe. Errors:
//   NotFound  - the id names nothing,
//   Conflict  - the request does not fit the current state (wrong offset, lost lease, ...),
//   Invalid   - the request itself is wrong (bad hash, bad name, ...),
//   StorageFull - no space left (the call kept nothing; reads keep working); file writes
//               may also throw std::system_error with ENOSPC or EDQUOT.
#pragma once

#include <cstdint>
#include <functional>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "proto/auth.h"
#include "proto/job.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"

namespace keel::storage {

struct NotFound : std::runtime_error { using std::runtime_error::runtime_error; };
struct Conflict : std::runtime_error { using std::runtime_error::runtime_error; };
struct Invalid : std::runtime_error { using std::runtime_error::runtime_error; };
// The database cannot be reached now (PostgreSQL down, network cut): nothing was changed,
// or the outcome of a commit is unknown; the caller may try again later (503).
struct Unavailable : std::runtime_error { using std::runtime_error::runtime_error; };
// The disk or the database is full: nothing of the call was kept (the server answers 507).
struct StorageFull : std::runtime_error { using std::runtime_error::runtime_error; };

// Refinements, so the server can choose the HTTP code (catching the base still works).
// append_upload: the chunk does not start at the committed offset (409 offset_mismatch).
struct OffsetMismatch : Conflict {
  OffsetMismatch(const std::string& message, int64_t committed)
      : Conflict(message), committed_offset(committed) {}
  int64_t committed_offset;  // where the client must resume (Upload-Offset header)
};
// Worker calls whose lease is not the job's current one (409 lease_lost).
struct LeaseLost : Conflict { using Conflict::Conflict; };
// complete_upload: the bytes do not match; the upload was deleted (422).
struct Sha256Mismatch : Invalid { using Invalid::Invalid; };
struct SizeMismatch : Invalid { using Invalid::Invalid; };

// Milliseconds since the Unix epoch; injectable so tests can move time (lease expiry).
using Clock = std::function<int64_t()>;
int64_t system_clock_ms();

struct JobFilter {
  std::optional<proto::JobState> state;
  std::string mission_id;    // "" = any
  int limit = 1000;
  std::string project;       // "" or "*" = any
  std::string batch_id;      // "" = any
  std::string mission_name;  // "" = any; else jobs whose mission name contains it (bytes)
};

// What a new token may do (the clear token is chosen by the caller, stored hashed).
struct TokenSpec {
  std::string label;
  proto::Role role = proto::Role::kViewer;
  std::string project = proto::kDefaultProject;  // or proto::kAllProjects
  int64_t expires_at_ms = 0;                     // 0 = never
};

// An admin token of every project (the first token a server makes; tests).
inline TokenSpec admin_token(std::string label) {
  TokenSpec spec;
  spec.label = std::move(label);
  spec.role = proto::Role::kAdmin;
  spec.project = proto::kAllProjects;
  return spec;
}

// A change committed to the store, for live views (GET /v1/events) and lease wake-ups.
// Delivered after the commit, on a thread of the store's choosing (the committing thread for
// SQLite; a listener thread for PostgreSQL, for changes made by any replica). Deliveries may
// be coalesced or repeated: a listener re-reads what it needs. Listeners must be quick and
// must not throw; they may call the store.
struct Change {
  enum class Kind { kJob, kLog };
  Kind kind = Kind::kJob;
  std::string job_id;
  std::string project;
  proto::JobState state = proto::JobState::kQueued;  // kJob: the state after the change
};
using ChangeListener = std::function<void(const Change&)>;

// Ends the subscription when destroyed (no call of its listener starts after that).
class Subscription {
 public:
  virtual ~Subscription() = default;
};

struct Metrics {
  int64_t jobs_by_state[5] = {0, 0, 0, 0, 0};  // indexed by proto::JobState
  int64_t missions = 0;
  int64_t blobs = 0;
  int64_t blob_bytes = 0;
  int64_t uploads_open = 0;
};

class Store {
 public:
  virtual ~Store() = default;

  // --- uploads (bytes go to a partial file next to the blob folder) ---
  // The upload belongs to request.project ("" = default).
  virtual proto::Upload create_upload(const proto::UploadRequest& request) = 0;
  virtual proto::Upload get_upload(const std::string& upload_id) = 0;
  // Appends `size` bytes at `offset`. Conflict unless offset == committed offset; Invalid if
  // offset + size exceeds the announced size. The chunk is durable (fsync) before return.
  // The upload's offset only moves once all bytes are written: a cut chunk commits nothing.
  virtual proto::Upload append_upload(const std::string& upload_id, int64_t offset,
                                      const char* data, size_t size) = 0;
  // Verifies size and SHA-256, moves the bytes into the blob store (same content, same blob)
  // and deletes the upload. On a wrong hash or size the upload is deleted too (nothing kept)
  // and Invalid is thrown.
  virtual std::string complete_upload(const std::string& upload_id, const std::string& sha256) = 0;
  virtual void delete_upload(const std::string& upload_id) = 0;

  // --- blobs (content-addressed files: write temp, fsync, rename) ---
  virtual bool has_blob(const std::string& sha256) = 0;
  virtual int64_t blob_size(const std::string& sha256) = 0;           // NotFound
  virtual std::filesystem::path blob_path(const std::string& sha256) = 0;  // NotFound
  // Stores bytes directly (small blobs, tests). Returns the SHA-256.
  virtual std::string put_blob(const std::string& bytes) = 0;

  // --- missions ---
  // In request.project ("" = default). NotFound for blobs.
  virtual proto::Mission create_mission(const proto::MissionRequest& request) = 0;
  virtual proto::Mission get_mission(const std::string& mission_id) = 0;
  // Newest first; the prefix matches names byte for byte (case-sensitive); project "" or "*"
  // = every project.
  virtual std::vector<proto::Mission> list_missions(const std::string& name_prefix = "",
                                                    const std::string& project = "") = 0;

  // --- jobs ---
  // With a non-empty idempotency key, a second call with the same key returns the first job
  // (and `created` false) instead of making a new one. The job takes its mission's project;
  // NotFound when the mission is unknown or request.project is set and differs from it.
  virtual proto::Job create_job(const proto::JobRequest& request, const std::string& idempotency_key,
                                bool* created = nullptr) = 0;
  virtual proto::Job get_job(const std::string& job_id) = 0;
  virtual std::vector<proto::Job> list_jobs(const JobFilter& filter) = 0;
  // queued -> canceled at once; running -> canceled (the worker learns it at its next
  // heartbeat). Conflict for a finished job.
  virtual proto::Job cancel_job(const std::string& job_id) = 0;
  // failed | canceled -> queued, keeping completed stages. Conflict otherwise.
  virtual proto::Job retry_job(const std::string& job_id) = 0;

  // --- reprocess batches ---
  // One job per matching mission of request.project (explicit ids, or names starting with
  // name_prefix; none = all), made in ONE transaction with one batch id. NotFound naming
  // `mission_ids[i]` for an id that is unknown or of another project, and then nothing is
  // made. Invalid when both ids and a prefix are given. The returned batch has `jobs` set.
  virtual proto::Batch create_batch(const proto::ReprocessRequest& request) = 0;
  virtual proto::Batch get_batch(const std::string& batch_id) = 0;  // counts by state now

  // --- worker protocol ---
  // Takes the oldest queued job of request.project ("" or "*" = any project), after
  // requeueing expired leases (attempts counts every lease). Never waits: the server's long
  // poll waits for a kJob change to kQueued and calls again. Records the worker as seen.
  // The lease is complete: the job, its mission, the stages earlier attempts finished, and a
  // compare job's input jobs (options.compare.job_a, job_b) with their artifacts.
  virtual std::optional<proto::Lease> lease_job(const proto::LeaseRequest& request) = 0;
  // The worker gives its lease back (SIGTERM, shutdown): running -> queued at once, keeping
  // completed stages; this lease is not counted as an expiry. LeaseLost as for heartbeats.
  virtual proto::Job release_job(const std::string& job_id, const std::string& lease_id) = 0;
  // Requeues (or fails, at the third expiry) every running job whose lease expired; any
  // replica may run it at any time. Returns how many jobs it changed.
  virtual int requeue_expired_leases() = 0;
  // Conflict when the lease is not the job's current one or has expired and was re-leased.
  virtual proto::HeartbeatReply heartbeat(const std::string& job_id, const proto::Heartbeat& beat) = 0;
  virtual proto::Artifact add_artifact(const std::string& job_id,
                                       const proto::ArtifactRegistration& registration) = 0;
  virtual void complete_stage(const std::string& job_id, const std::string& stage,
                              const proto::StageCompletion& completion) = 0;
  virtual proto::Job finish_job(const std::string& job_id, const proto::JobFinish& finish,
                                bool succeeded) = 0;

  // --- artifacts and logs ---
  virtual std::vector<proto::Artifact> list_artifacts(const std::string& job_id) = 0;
  virtual proto::Artifact get_artifact(const std::string& artifact_id) = 0;
  virtual void append_log(const std::string& job_id, const std::vector<std::string>& lines) = 0;
  virtual proto::LogPage read_log(const std::string& job_id, int64_t from, int limit = 1000) = 0;

  // --- API tokens (stored as SHA-256 hashes, never in clear) ---
  // Invalid for an empty token, a bad project name, or "*" for a submitter/viewer; the
  // token's project is created when new. Adding the same token twice keeps the first.
  virtual proto::TokenInfo add_token(const std::string& token, const TokenSpec& spec) = 0;
  // The token's record, or nullopt when it is unknown, revoked or expired.
  virtual std::optional<proto::TokenInfo> check_token(const std::string& token) = 0;
  virtual std::vector<proto::TokenInfo> list_tokens() = 0;  // oldest first, revoked included
  virtual proto::TokenInfo revoke_token(const std::string& token_id) = 0;  // NotFound
  virtual int64_t token_count() = 0;

  // --- projects ---
  virtual std::vector<proto::Project> list_projects() = 0;  // by name
  virtual proto::Project ensure_project(const std::string& name) = 0;  // Invalid for a bad name
  // Sets the project's quota (bytes stored, 0 = none), creating the project when new.
  virtual proto::Project set_project_quota(const std::string& name, int64_t quota_bytes) = 0;
  // Bytes the project holds: each distinct blob it references once (uploaded through its
  // uploads, named by its missions, or an artifact of its jobs) plus the announced size of
  // its open uploads (space they will take). 0 for an unknown project.
  virtual int64_t project_usage(const std::string& name) = 0;
  // True when the project references the blob (see project_usage): a token of one project
  // fetches only those blobs, so a hash cannot probe another project's data.
  virtual bool project_has_blob(const std::string& name, const std::string& sha256) = 0;

  // --- live changes and the queue ---
  virtual std::unique_ptr<Subscription> subscribe(ChangeListener listener) = 0;
  // Counts by state, workers seen in the last hour (alive = seen in the last 60 s), and the
  // last hour's throughput.
  virtual proto::QueueSummary queue_summary() = 0;

  virtual Metrics metrics() = 0;
};

// Opens (creating if needed) a SQLite store in `data_dir`: keel.db (WAL, foreign keys,
// schema_version + migrations), blobs/ (content-addressed), uploads/ (partial files).
std::unique_ptr<Store> open_sqlite_store(const std::filesystem::path& data_dir,
                                         Clock clock = system_clock_ms);

}  // namespace keel::storage
