#include "client/job_watcher.h"

#include <chrono>
#include <cstdio>
#include <thread>

#include "client/exit_codes.h"
#include "client/progress_bar.h"

namespace keel::client {

namespace {

int exit_code_of(const proto::Job& job) {
  switch (job.state) {
    case proto::JobState::kFailed:
      return kExitJobFailed;
    case proto::JobState::kCanceled:
      return kExitJobCanceled;
    default:
      return kExitOk;
  }
}

// "stage ingest (2/3)  [#####.....] 45%": the bar for a running job on a terminal.
std::string stage_line(const proto::Job& job) {
  std::string text = proto::to_string(job.state);
  if (!job.stage.empty()) {
    text += " " + job.stage;
    for (size_t i = 0; i < job.stages.size(); ++i)
      if (job.stages[i] == job.stage)
        text += " (" + std::to_string(i + 1) + "/" + std::to_string(job.stages.size()) + ")";
  }
  const int width = 30;
  const int filled = static_cast<int>(width * std::min(1.0, std::max(0.0, job.progress)));
  text += "  [" + std::string(filled, '#') + std::string(width - filled, '.') + "] " +
          std::to_string(static_cast<int>(100 * job.progress)) + "%";
  return text;
}

}  // namespace

int64_t print_log(ApiClient& api, const std::string& job_id, int64_t from) {
  while (true) {
    const proto::LogPage page = api.read_log(job_id, from);
    for (const auto& line : page.lines) std::printf("%s\n", line.text.c_str());
    std::fflush(stdout);
    if (page.lines.empty() || page.next <= from) return from;
    from = page.next;
  }
}

int watch_job(ApiClient& api, const std::string& job_id, const WatchOptions& options) {
  const bool terminal = is_terminal(stderr);
  int64_t next_line = options.log_from;
  std::string last_status;
  while (true) {
    const proto::Job job = api.get_job(job_id);
    // Lines first, then the status, so the bar stays the last line of the terminal.
    if (terminal && !last_status.empty()) std::fprintf(stderr, "\r\033[K");
    next_line = print_log(api, job_id, next_line);
    const std::string status = stage_line(job);
    if (options.show_progress) {
      if (terminal) {
        std::fprintf(stderr, "\r%s\033[K", status.c_str());
      } else if (status != last_status) {
        std::fprintf(stderr, "%s\n", status.c_str());
      }
      std::fflush(stderr);
    }
    last_status = status;
    if (proto::is_terminal(job.state)) {
      if (terminal && options.show_progress) std::fprintf(stderr, "\n");
      std::fprintf(stderr, "job %s %s%s\n", job.id.c_str(), proto::to_string(job.state).c_str(),
                   job.error.empty() ? "" : (": " + job.error).c_str());
      return exit_code_of(job);
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(options.poll_interval_s));
  }
}

}  // namespace keel::client
