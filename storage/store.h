// Keel's durable state behind one interface: uploads, blobs, missions, jobs with leases,
// stage outputs, artifacts, job logs and API tokens. The server calls only this interface,
// so a PostgreSQL implementation can be added later without changing callers.
//
// Every method is atomic (one transaction) and thread-safe. Errors:
//   NotFound  - the id names nothing,
//   Conflict  - the request does not fit the current state (wrong offset, lost lease, ...),
//   Invalid   - the request itself is wrong (bad hash, bad name, ...).
#pragma once

#include <cstdint>
#include <functional>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "proto/job.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"

namespace keel::storage {

struct NotFound : std::runtime_error { using std::runtime_error::runtime_error; };
struct Conflict : std::runtime_error { using std::runtime_error::runtime_error; };
struct Invalid : std::runtime_error { using std::runtime_error::runtime_error; };

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
  std::string mission_id;  // "" = any
  int limit = 1000;
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
  virtual proto::Mission create_mission(const proto::MissionRequest& request) = 0;  // NotFound for blobs
  virtual proto::Mission get_mission(const std::string& mission_id) = 0;
  // Newest first; the prefix matches names byte for byte (case-sensitive).
  virtual std::vector<proto::Mission> list_missions(const std::string& name_prefix = "") = 0;

  // --- jobs ---
  // With a non-empty idempotency key, a second call with the same key returns the first job
  // (and `created` false) instead of making a new one.
  virtual proto::Job create_job(const proto::JobRequest& request, const std::string& idempotency_key,
                                bool* created = nullptr) = 0;
  virtual proto::Job get_job(const std::string& job_id) = 0;
  virtual std::vector<proto::Job> list_jobs(const JobFilter& filter) = 0;
  // queued -> canceled at once; running -> canceled (the worker learns it at its next
  // heartbeat). Conflict for a finished job.
  virtual proto::Job cancel_job(const std::string& job_id) = 0;
  // failed | canceled -> queued, keeping completed stages. Conflict otherwise.
  virtual proto::Job retry_job(const std::string& job_id) = 0;

  // --- worker protocol ---
  // Takes the oldest queued job, or a running job whose lease expired (attempts counts both).
  virtual std::optional<proto::Lease> lease_job(const proto::LeaseRequest& request) = 0;
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
  virtual void add_token(const std::string& token, const std::string& label) = 0;
  virtual bool check_token(const std::string& token) = 0;
  virtual int64_t token_count() = 0;

  virtual Metrics metrics() = 0;
};

// Opens (creating if needed) a SQLite store in `data_dir`: keel.db (WAL, foreign keys,
// schema_version + migrations), blobs/ (content-addressed), uploads/ (partial files).
std::unique_ptr<Store> open_sqlite_store(const std::filesystem::path& data_dir,
                                         Clock clock = system_clock_ms);

}  // namespace keel::storage
