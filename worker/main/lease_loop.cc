#include "worker/main/lease_loop.h"

#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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

void release_unstarted(client::ApiClient& api, const proto::Lease& lease) {
  try {
    api.release_job(lease.job.id, lease.lease_id);
    spdlog::info("job {}: lease given back unrun (stopping)", lease.job.id);
  } catch (const std::exception& e) {
    spdlog::warn("job {}: could not give the lease back ({}); it will expire", lease.job.id,
                 e.what());
  }
}

bool process_alive(long pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

// Workers started together (keel-server --workers N) share one cache folder: blobs are
// shared, but job folders and upload state belong to one process, in "work-<pid>". The
// folders of processes that are gone (killed, crashed) are removed.
std::filesystem::path make_process_area(const std::filesystem::path& cache_dir) {
  std::error_code ec;
  std::filesystem::create_directories(cache_dir);
  for (const auto& item : std::filesystem::directory_iterator(cache_dir, ec)) {
    const std::string name = item.path().filename().string();
    if (name.rfind("work-", 0) != 0) continue;
    if (!process_alive(std::atol(name.c_str() + 5))) std::filesystem::remove_all(item.path(), ec);
  }
  const auto area = cache_dir / ("work-" + std::to_string(::getpid()));
  std::filesystem::create_directories(area / "jobs");
  std::filesystem::create_directories(area / "uploads");
  return area;
}

}  // namespace

std::string default_worker_name() {
  static const int64_t start_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                                      std::chrono::system_clock::now().time_since_epoch())
                                      .count();
  char host[256] = {};
  if (::gethostname(host, sizeof(host) - 1) != 0) std::snprintf(host, sizeof(host), "unknown");
  return std::string(host) + ":" + std::to_string(::getpid()) + ":" + std::to_string(start_ms);
}

LeaseLoop::LeaseLoop(client::ClientConfig config, LeaseLoopOptions options,
                     pipeline::StageFactory factory)
    : config_(std::move(config)), options_(std::move(options)), factory_(std::move(factory)) {
  if (options_.worker_name.empty()) options_.worker_name = default_worker_name();
}

int LeaseLoop::run(const std::function<bool()>& stop_requested) {
  client::ApiClient api(config_);
  // ApiClient is not thread-safe: one per thread. A heartbeat that hangs longer than a
  // third of the lease is useless, and it would hold up stopping.
  client::ClientConfig heartbeat_config = config_;
  heartbeat_config.timeout_s =
      std::min(config_.timeout_s, std::max(2.0, options_.lease_seconds / 3.0));
  client::ApiClient heartbeat_api(heartbeat_config);
  BlobCache blobs(options_.cache_dir / "blobs");
  const std::filesystem::path area = make_process_area(options_.cache_dir);
  auto remove_area = [&] {
    std::error_code ec;
    if (!options_.keep_work) std::filesystem::remove_all(area, ec);
  };
  LeasedJobOptions job_options;
  job_options.jobs_dir = area / "jobs";
  job_options.uploads_dir = area / "uploads";
  job_options.heartbeat_seconds = options_.heartbeat_seconds;
  job_options.lease_seconds = options_.lease_seconds;
  job_options.keep_work = options_.keep_work;

  proto::LeaseRequest request;
  request.worker = options_.worker_name;
  request.lease_seconds = options_.lease_seconds;
  // The server holds the call up to wait_seconds: keep it well inside the request deadline.
  request.wait_seconds =
      std::max(0, std::min(options_.wait_seconds, static_cast<int>(config_.timeout_s) - 5));
  spdlog::info("worker {} leasing from {} (long poll {} s)", request.worker, config_.url,
               request.wait_seconds);

  using Clock = std::chrono::steady_clock;
  auto idle_since = Clock::now();
  auto idle_long_enough = [&] {
    return options_.exit_when_idle_s > 0 &&
           std::chrono::duration<double>(Clock::now() - idle_since).count() >=
               options_.exit_when_idle_s;
  };
  int failures = 0;
  while (!stop_requested()) {
    if (idle_long_enough()) {
      spdlog::info("no job for {:.0f} s: exiting (--exit-when-idle)", options_.exit_when_idle_s);
      break;
    }
    std::optional<proto::Lease> lease;
    try {
      lease = api.lease(request);
      if (failures > 0) spdlog::info("server reachable again");
      failures = 0;
    } catch (const client::ApiCallError& e) {
      if (e.status() == 401) {
        spdlog::error("the server rejected the token: {}", e.what());
        remove_area();
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
      if (request.wait_seconds == 0) pause(options_.poll_seconds, stop_requested);
      continue;
    }
    if (stop_requested()) {
      // Leased while the stop was asked (the long poll answered late): give it back unrun.
      release_unstarted(api, *lease);
      break;
    }
    LeasedJob(api, heartbeat_api, blobs, *lease, job_options, factory_, stop_requested).run();
    idle_since = Clock::now();
    if (options_.once) break;
  }
  if (stop_requested()) spdlog::info("stopping");
  remove_area();
  return 0;
}

}  // namespace keel::worker
