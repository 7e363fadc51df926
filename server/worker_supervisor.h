// Runs N local keel-worker processes next to the server and keeps them running: a worker
// that exits on its own is started again after a backoff (doubling up to max_backoff, reset
// once a worker has run for stable_after). stop() sends SIGTERM to all, waits stop_grace,
// then SIGKILLs what is left and reaps everything.
//
// Workers are started with posix_spawn in their own process group (a Ctrl-C in the server's
// terminal reaches only the server, which then stops them in order), with the default signal
// mask and dispositions, stdin from /dev/null and stdout+stderr appended to
// <log_dir>/worker-<i>.log.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace keel::server {

struct SupervisorOptions {
  int workers = 1;
  std::filesystem::path worker_binary;
  std::filesystem::path log_dir;
  std::chrono::milliseconds initial_backoff{500};
  std::chrono::milliseconds max_backoff{30'000};
  std::chrono::milliseconds stable_after{60'000};
  std::chrono::milliseconds stop_grace{10'000};
  std::chrono::milliseconds poll_interval{100};
};

class WorkerSupervisor {
 public:
  explicit WorkerSupervisor(SupervisorOptions options);
  ~WorkerSupervisor();  // stops
  WorkerSupervisor(const WorkerSupervisor&) = delete;
  WorkerSupervisor& operator=(const WorkerSupervisor&) = delete;

  // Starts the workers, each as `worker_binary worker_args...` (e.g. --server URL
  // --token-file F; known only once the server is bound), and the monitoring thread. Throws
  // std::runtime_error when the binary is not executable or the log folder cannot be made.
  void start(std::vector<std::string> worker_args);
  void stop();  // idempotent

  int alive() const;                // workers running now
  std::vector<pid_t> pids() const;  // 0 for a slot waiting to restart
  int restarts() const;             // unexpected exits seen so far

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel::server
