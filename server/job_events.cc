#include "server/job_events.h"

#include <nlohmann/json.hpp>

namespace keel::server {

std::string sse_event(const std::string& type, const std::string& data) {
  return "event: " + type + "\ndata: " + data + "\n\n";
}

JobEvents::JobEvents(storage::Store& store, proto::TokenInfo reader, JobEventsOptions options)
    : store_(store), reader_(std::move(reader)), options_(std::move(options)) {}

JobEvents::~JobEvents() { subscription_.reset(); }

void JobEvents::start(std::function<void()> wake) {
  wake_ = std::move(wake);
  last_sent_ = std::chrono::steady_clock::now();
  subscription_ = store_.subscribe([this](const storage::Change& change) { on_change(change); });
}

std::chrono::milliseconds JobEvents::tick() const { return options_.ping_interval; }

void JobEvents::on_change(const storage::Change& change) {
  // Another project's changes are not even counted: the stream leaks nothing about them.
  if (!reader_.reaches(change.project)) return;
  if (!options_.job_id.empty() && change.job_id != options_.job_id) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (change.job_id.empty())
      reload_ = true;
    else if (change.kind == storage::Change::Kind::kLog)
      logged_jobs_.insert(change.job_id);
    else
      changed_jobs_.insert(change.job_id);
  }
  if (wake_) wake_();
}

std::string JobEvents::job_event(const std::string& job_id) {
  try {
    const proto::Job job = store_.get_job(job_id);
    if (!reader_.reaches(job.project)) return "";
    return sse_event("job", job.to_json().dump());
  } catch (const storage::NotFound&) {
    return "";
  }
}

std::string JobEvents::take(bool final, bool& ended) {
  std::string out;
  if (!hello_sent_) {
    hello_sent_ = true;
    const int64_t now = options_.now_ms ? options_.now_ms() : 0;
    out += sse_event("hello", nlohmann::json{{"server_time_ms", now}}.dump());
  }
  std::set<std::string> jobs, logs;
  bool reload = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs.swap(changed_jobs_);
    logs.swap(logged_jobs_);
    std::swap(reload, reload_);
  }
  if (reload) out += sse_event("reload", "{}");
  for (const std::string& job_id : jobs) out += job_event(job_id);
  for (const std::string& job_id : logs)
    out += sse_event("log", nlohmann::json{{"job_id", job_id}}.dump());
  const auto now = std::chrono::steady_clock::now();
  if (out.empty() && now - last_sent_ >= options_.ping_interval) out = ": ping\n\n";
  if (!out.empty()) last_sent_ = now;
  ended = final;
  return out;
}

}  // namespace keel::server
