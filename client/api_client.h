// A blocking HTTP client for Keel's API v1 (Boost.Beast), used by the `keel` CLI and by
// `keel-worker`. Every call has a deadline; non-2xx answers throw ApiCallError carrying the
// server's {"error": {"code", "message"}}.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "proto/job.h"
#include "proto/resources.h"
#include "proto/worker_protocol.h"

namespace keel::client {

struct ClientConfig {
  std::string url = "http://127.0.0.1:8080";  // http[s]://host:port
  std::string token;
  std::string ca_file;             // https: PEM CAs to trust instead of the system's
  double timeout_s = 60.0;         // deadline of one request
  int64_t chunk_bytes = 16 << 20;  // upload chunk size
  int retries = 5;                 // reconnect attempts on a dropped link (uploads, downloads)
  double retry_backoff_s = 0.25;   // first pause after a failure; doubles, capped at 5 s
};

// Body bytes moved by one ApiClient since its construction (tests check resume with these).
struct TransferStats {
  int64_t upload_body_bytes = 0;    // PUT chunk bodies written to the socket
  int64_t download_body_bytes = 0;  // download bodies written to `.part` files
  int64_t connections = 0;          // TCP connections opened (reconnects included)
};

// A non-2xx answer (status > 0) or a transport failure (status 0).
class ApiCallError : public std::runtime_error {
 public:
  ApiCallError(int status, std::string code, const std::string& message)
      : std::runtime_error(message), status_(status), code_(std::move(code)) {}
  int status() const { return status_; }
  const std::string& code() const { return code_; }

 private:
  int status_;
  std::string code_;
};

struct HttpResult {
  int status = 0;
  std::map<std::string, std::string> headers;  // lower-case names
  std::string body;
};

// Bytes done, bytes total.
using ProgressFn = std::function<void(int64_t done, int64_t total)>;

class ApiClient {
 public:
  explicit ApiClient(ClientConfig config);
  ~ApiClient();
  ApiClient(const ApiClient&) = delete;
  ApiClient& operator=(const ApiClient&) = delete;

  const ClientConfig& config() const { return config_; }
  const TransferStats& stats() const { return stats_; }

  // Raw request on a kept-alive connection (reconnects when the server closed it).
  // Does not throw on non-2xx; throws ApiCallError(0, "transport", ...) when unreachable.
  HttpResult request(const std::string& method, const std::string& target,
                     const std::string& body = "",
                     const std::map<std::string, std::string>& headers = {});
  // JSON helpers: throw ApiCallError on non-2xx.
  nlohmann::json get_json(const std::string& target);
  nlohmann::json post_json(const std::string& target, const nlohmann::json& body,
                           const std::map<std::string, std::string>& headers = {});

  // Uploads `file` resumably and returns its blob id (SHA-256). The upload id is remembered
  // in `state_dir` (keyed by the file's SHA-256 and size), so running it again after a
  // dropped link or a killed client resumes at the server's committed offset.
  // `known_sha256` skips hashing the file first when the caller already knows its hash
  // (the server still checks it on completion: a wrong one gives 422 sha256_mismatch).
  // `project` names the project the upload counts against ("" = the token's; a worker names
  // its job's, so artifacts count against the job's project quota).
  // progress(offset, size) is called once at the start and after every committed chunk;
  // an exception thrown from it ends the upload, leaving it resumable.
  std::string upload_file(const std::filesystem::path& file, const std::filesystem::path& state_dir,
                          const ProgressFn& progress = {}, const std::string& known_sha256 = "",
                          const std::string& project = "");
  // Downloads a GET target (artifact or blob) to `destination` with Range resume: bytes go
  // to `destination.part` first and it is renamed when complete and its SHA-256 matches
  // `expected_sha256` (when given). A mismatch throws ApiCallError(0, "sha256_mismatch")
  // and deletes the part, so the next attempt starts clean.
  void download(const std::string& target, const std::filesystem::path& destination,
                const std::string& expected_sha256 = "", const ProgressFn& progress = {});

  // --- client API ---
  proto::Mission create_mission(const proto::MissionRequest& request);
  std::vector<proto::Mission> list_missions(const std::string& prefix = "");
  proto::Job create_job(const proto::JobRequest& request, const std::string& idempotency_key = "");
  proto::Job get_job(const std::string& job_id);
  std::vector<proto::Job> list_jobs(const std::string& state = "");
  proto::Job cancel_job(const std::string& job_id);
  proto::Job retry_job(const std::string& job_id);
  // POST /v1/reprocess: the batch (made in one transaction) and, for batches of up to
  // 1,000 jobs, its jobs.
  struct Reprocessed {
    proto::Batch batch;
    std::vector<proto::Job> jobs;
  };
  Reprocessed reprocess(const proto::ReprocessRequest& request);
  proto::Batch get_batch(const std::string& batch_id);
  // GET /v1/jobs?batch_id=: the batch's jobs, newest first (at most `limit`).
  std::vector<proto::Job> list_batch_jobs(const std::string& batch_id, int limit = 10000);
  proto::LogPage read_log(const std::string& job_id, int64_t from);
  std::vector<proto::Artifact> list_artifacts(const std::string& job_id);

  // --- worker API ---
  std::optional<proto::Lease> lease(const proto::LeaseRequest& request);  // nullopt on 204
  proto::HeartbeatReply heartbeat(const std::string& job_id, const proto::Heartbeat& beat);
  proto::Artifact register_artifact(const std::string& job_id,
                                    const proto::ArtifactRegistration& reg);
  void complete_stage(const std::string& job_id, const std::string& stage,
                      const proto::StageCompletion& completion);
  proto::Job finish_job(const std::string& job_id, const proto::JobFinish& finish, bool succeeded);
  // Gives the lease back (the worker is stopping): the job is queued again at once.
  proto::Job release_job(const std::string& job_id, const std::string& lease_id);

 private:
  struct Connection;
  HttpResult request_or_throw(const std::string& method, const std::string& target,
                              const std::string& body,
                              const std::map<std::string, std::string>& headers);
  std::optional<int64_t> upload_offset(const std::string& upload_id);
  std::string create_upload(const std::string& name, int64_t size, const std::string& project);
  HttpResult put_chunk(const std::string& upload_id, const char* data, int64_t first, int64_t size,
                       int64_t total);
  bool blob_exists(const std::string& sha256);
  // One GET attempt appending to `part`; returns false when the part had to be restarted.
  bool download_once(const std::string& target, const std::filesystem::path& part,
                     const ProgressFn& progress);
  void pause_before_retry(int failures) const;

  ClientConfig config_;
  TransferStats stats_;
  std::unique_ptr<Connection> connection_;
};

}  // namespace keel::client
