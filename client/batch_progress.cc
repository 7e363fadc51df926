#include "client/batch_progress.h"

#include <cmath>
#include <cstdio>

namespace keel::client {

namespace {

int64_t count(const proto::Batch& batch, const char* state) {
  auto found = batch.jobs_by_state.find(state);
  return found == batch.jobs_by_state.end() ? 0 : found->second;
}

}  // namespace

std::optional<double> batch_eta_seconds(const proto::Batch& batch) {
  const int64_t queued = count(batch, "queued");
  const int64_t running = count(batch, "running");
  if (queued + running == 0) return 0.0;
  if (batch.finished_jobs_timed == 0 || running == 0) return std::nullopt;
  return batch.mean_job_seconds * (static_cast<double>(queued) + running / 2.0) /
         static_cast<double>(running);
}

std::string format_duration_s(double seconds) {
  const int64_t total = static_cast<int64_t>(std::llround(std::max(0.0, seconds)));
  char text[64];
  if (total >= 3600)
    std::snprintf(text, sizeof(text), "%ldh %02ldm", long(total / 3600), long(total % 3600 / 60));
  else if (total >= 60)
    std::snprintf(text, sizeof(text), "%ldm %02lds", long(total / 60), long(total % 60));
  else
    std::snprintf(text, sizeof(text), "%lds", long(total));
  return text;
}

bool batch_finished(const proto::Batch& batch) {
  return count(batch, "queued") + count(batch, "running") == 0;
}

std::string format_batch_status(const proto::Batch& batch) {
  std::string out =
      "batch " + batch.id + " (" + batch.project + "): " + std::to_string(batch.jobs) + " jobs";
  for (const char* state : {"queued", "running", "succeeded", "failed", "canceled"})
    out += ", " + std::to_string(count(batch, state)) + " " + state;
  out += "\n";
  if (batch_finished(batch)) return out + "finished\n";
  char line[160];
  if (batch.finished_jobs_timed == 0) {
    std::snprintf(line, sizeof(line), "no job finished yet: no ETA\n");
  } else {
    const auto eta = batch_eta_seconds(batch);
    std::snprintf(line, sizeof(line), "mean job %.1f s over %ld finished; ETA %s\n",
                  batch.mean_job_seconds, long(batch.finished_jobs_timed),
                  eta ? format_duration_s(*eta).c_str() : "unknown (no job running)");
  }
  return out + line;
}

}  // namespace keel::client
