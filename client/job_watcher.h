// Follows a job until it ends: stage and progress on stderr, new log lines on stdout.
// Used by `keel watch`, `keel log --follow` and `keel submit --wait`.
#pragma once

#include <cstdint>
#include <string>

#include "client/api_client.h"
#include "client/cli_defaults.h"

namespace keel::client {

struct WatchOptions {
  double poll_interval_s = kDefaultPollInterval_s;
  bool show_progress = true;  // the stage progress bar on stderr
  int64_t log_from = 0;       // first log line to print
};

// Returns the exit code for the terminal state: 0 succeeded, kExitJobFailed,
// kExitJobCanceled. ApiCallError propagates.
int watch_job(ApiClient& api, const std::string& job_id, const WatchOptions& options);

// Prints log lines from `from` until the end; returns the next line number.
int64_t print_log(ApiClient& api, const std::string& job_id, int64_t from);

}  // namespace keel::client
