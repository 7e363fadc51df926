#include "worker/main/lease_loop.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <thread>

#include "worker/main/blob_cache.h"
#include "worker/main/leased_job.h"

namespace keel::worker {

namespace {

// Sleeps up to `seconds`, waking early when asked to stop.
void pause(double seconds, const std::function<bool()>& stop_requested) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!stop_requested() && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

}  // namespace

std::string default_worker_name() {
  char host[256] = {};
  if (::gethostname(host, sizeof(host) - 1) != 0) std::snprintf(host, sizeof(host), "unknown");
  return std::string(host) + ":" + std::to_string(::getpid());
}

LeaseLoop::LeaseLoop(client::ClientConfig config, LeaseLoopOptions options,
                     pipeline::StageFactory factory)
    : config_(std::move(config)), options_(std::move(options)), factory_(std::move(factory)) {
  if (options_.worker_name.empty()) options_.worker_name = default_worker_name();
}

int LeaseLoop::run(const std::function<bool()>& stop_requested) {
  client::ApiClient api(config_);
  client::ApiClient heartbeat_api(config_);  // ApiClient is not thread-safe: one per thread
  BlobCache blobs(options_.cache_dir / "blobs");
  LeasedJobOptions job_options;
  job_options.jobs_dir = options_.cache_dir / "jobs";
  job_options.uploads_dir = options_.cache_dir / "uploads";
  job_options.heartbeat_seconds = options_.heartbeat_seconds;
  job_options.keep_work = options_.keep_work;
  std::filesystem::create_directories(job_options.jobs_dir);
  std::filesystem::create_directories(job_options.uploads_dir);

  proto::LeaseRequest request;
  request.worker = options_.worker_name;
  request.lease_seconds = options_.lease_seconds;
  spdlog::info("worker {} polling {}", request.worker, config_.url);

  int failures = 0;
  while (!stop_requested()) {
    std::optional<proto::Lease> lease;
    try {
      lease = api.lease(request);
      if (failures > 0) spdlog::info("server reachable again");
      failures = 0;
    } catch (const client::ApiCallError& e) {
      if (e.status() == 401) {
        spdlog::error("the server rejected the token: {}", e.what());
        return 1;
      }
      // Exponential backoff from poll_seconds up to max_backoff_seconds.
      const double wait = std::min(options_.max_backoff_seconds,
                                   options_.poll_seconds * std::pow(2.0, std::min(failures, 20)));
      if (failures++ % 10 == 0)
        spdlog::warn("lease failed ({}); retrying in {:.1f} s", e.what(), wait);
      pause(wait, stop_requested);
      continue;
    } catch (const std::exception& e) {
      // A reply that does not match the contract: log it and try again later.
      spdlog::error("lease failed: {}", e.what());
      pause(options_.max_backoff_seconds, stop_requested);
      continue;
    }
    if (!lease) {
      pause(options_.poll_seconds, stop_requested);
      continue;
    }
    LeasedJob(api, heartbeat_api, blobs, *lease, job_options, factory_, stop_requested).run();
    ++jobs_handled_;
    if (options_.once) break;
  }
  if (stop_requested()) spdlog::info("stopping");
  return 0;
}

}  // namespace keel::worker
