// `keel-worker serve`: lease a job, run it (LeasedJob), lease the next, until asked to stop.
// Leasing is a long poll: the server answers as soon as a job is queued (on any replica) or
// after wait_seconds with nothing. The server may be unreachable for a while (restarts,
// network): leasing retries with exponential backoff and never gives up. A 401 is a
// configuration error and ends the loop. On a stop request (SIGTERM) the running job stops
// at its next safe point and its lease is given back, so it is queued again at once.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "client/api_client.h"
#include "worker/pipeline/job_runner.h"

namespace keel::worker {

struct LeaseLoopOptions {
  std::string worker_name;          // "host:pid:start" by default (unique per process start)
  std::filesystem::path cache_dir;  // blobs/ (shared) and work-<pid>/ (jobs, uploads)
  int lease_seconds = 30;
  int wait_seconds = 10;              // long poll: how long the server may hold a lease call
  double poll_seconds = 1.0;          // pause when no job is queued (wait_seconds 0)
  double exit_when_idle_s = 0;        // > 0: return after this long without a job
  double heartbeat_seconds = 1.0;     // cancel is honoured within ~2 heartbeats
  double max_backoff_seconds = 30.0;  // longest pause between retries on server trouble
  bool once = false;                  // handle one job (waiting for it), then return
  bool keep_work = false;             // keep each job's folder (debugging)
};

// "hostname:pid:start", start = this process's start time in epoch ms: a pid reused on the
// same host (a restarted container, a Slurm array task) still gives a new name.
std::string default_worker_name();

class LeaseLoop {
 public:
  LeaseLoop(client::ClientConfig config, LeaseLoopOptions options,
            pipeline::StageFactory factory = {});

  // Runs until stop_requested() turns true (or after one job with `once`). Returns the
  // process exit code: 0, or 1 when the server rejects the token.
  int run(const std::function<bool()>& stop_requested);

 private:
  client::ClientConfig config_;
  LeaseLoopOptions options_;
  pipeline::StageFactory factory_;
};

}  // namespace keel::worker
