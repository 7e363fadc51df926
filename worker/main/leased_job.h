// One leased job, start to end:
//   1. start the heartbeat (progress, log lines, cancel, lease);
//   2. fetch the mission bundle (cached by SHA-256) and unpack it into a per-job folder;
//      fetch the CAD mesh, if any; download the artifacts of stages finished by earlier
//      attempts into the work folder, so the job resumes after them;
//   3. run the JobRunner; after each stage upload and register its artifacts (and, after
//      the last one, report.json and report.html), then post the stage's completion;
//   4. post complete or fail (a stage's failure first uploads report.json and report.html of
//      the stages that finished, with the error, under the job's last stage).
// Nothing escapes run(): a job's error fails that job only. Server trouble (unreachable,
// 5xx, lease lost) abandons the job instead: its lease expires and another worker resumes
// it after its last completed stage. A stop request (SIGTERM) stops the job at its next
// safe point (between stages, or where a stage checks for cancelation) and gives the lease
// back, so the job is queued again at once.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>

#include "client/api_client.h"
#include "proto/worker_protocol.h"
#include "worker/main/blob_cache.h"
#include "worker/pipeline/job_runner.h"
#include "worker/pipeline/report.h"

namespace keel::worker {

class JobHeartbeat;

struct LeasedJobOptions {
  std::filesystem::path jobs_dir;     // per-job folders live here
  std::filesystem::path uploads_dir;  // resumable-upload state of ApiClient::upload_file
  double heartbeat_seconds = 1.0;
  double lease_seconds = 30.0;  // the lease asked for: how long giving it back may be retried
  bool keep_work = false;       // keep the job's folder afterwards (debugging)
};

enum class JobEnd { kSucceeded, kFailed, kCanceled, kAbandoned, kReleased };
std::string to_string(JobEnd end);

class LeasedJob {
 public:
  // `api` serves this thread, `heartbeat_api` the heartbeat thread.
  LeasedJob(client::ApiClient& api, client::ApiClient& heartbeat_api, BlobCache& blobs,
            const proto::Lease& lease, const LeasedJobOptions& options,
            pipeline::StageFactory factory, std::function<bool()> stop_requested);

  JobEnd run();

 private:
  pipeline::JobSpec prepare();
  void download_completed_artifacts(const std::filesystem::path& work_dir);
  void on_stage_done(const std::string& stage, const pipeline::StageResult& result, double seconds);
  void upload_artifact(const std::string& stage, const std::string& name);
  void upload_report_files(const pipeline::JobResult& result);
  JobEnd finish(const pipeline::JobResult& result);
  JobEnd fail(const std::string& error);
  JobEnd abandon(const std::string& why);
  // The worker is stopping: the lease goes back to the server, asked again while the server
  // is unreachable or failing, for up to lease_seconds (abandoned after that, or on a 4xx).
  JobEnd give_back(const std::string& why);
  void log(const std::string& line);

  client::ApiClient& api_;
  client::ApiClient& heartbeat_api_;
  BlobCache& blobs_;
  const proto::Lease& lease_;
  const LeasedJobOptions& options_;
  pipeline::StageFactory factory_;
  std::function<bool()> stop_requested_;

  std::filesystem::path job_dir_;
  std::filesystem::path work_dir_;
  JobHeartbeat* heartbeat_ = nullptr;  // while run() runs
};

}  // namespace keel::worker
