#include "worker/main/job_heartbeat.h"

#include <spdlog/spdlog.h>

#include <chrono>

namespace keel::worker {

namespace {

// The server takes JSON bodies up to 1 MiB: bound what one beat carries.
constexpr size_t kMaxLinesPerBeat = 500;
constexpr size_t kMaxLineBytes = 1000;
// Lines kept while the server is unreachable; older ones are dropped first.
constexpr size_t kMaxQueuedLines = 20000;

}  // namespace

JobHeartbeat::JobHeartbeat(client::ApiClient& api, std::string job_id, std::string lease_id,
                           double period_s)
    : api_(api), job_id_(std::move(job_id)), lease_id_(std::move(lease_id)), period_s_(period_s) {}

JobHeartbeat::~JobHeartbeat() { stop(); }

void JobHeartbeat::start() {
  if (thread_.joinable()) return;
  thread_ = std::thread([this] { loop(); });
}

void JobHeartbeat::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void JobHeartbeat::set_stage(const std::string& stage) {
  std::lock_guard<std::mutex> lock(mutex_);
  stage_ = stage;
  progress_ = 0.0;
}

void JobHeartbeat::set_progress(double progress) {
  std::lock_guard<std::mutex> lock(mutex_);
  progress_ = progress;
}

void JobHeartbeat::log(const std::string& line) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.push_back(line.size() > kMaxLineBytes ? line.substr(0, kMaxLineBytes) + "..." : line);
  while (pending_.size() > kMaxQueuedLines) pending_.pop_front();
}

void JobHeartbeat::loop() {
  const auto period = std::chrono::duration<double>(period_s_);
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, period, [this] { return stopping_; });
    if (stopping_) break;
    lock.unlock();
    beat(api_);
    lock.lock();
  }
}

bool JobHeartbeat::flush(client::ApiClient& api) {
  bool ok = true;
  // Several beats when more lines are queued than one beat carries.
  do {
    ok = beat(api);
  } while (ok && [this] {
    std::lock_guard<std::mutex> lock(mutex_);
    return !pending_.empty();
  }());
  return ok;
}

bool JobHeartbeat::beat(client::ApiClient& api) {
  proto::Heartbeat message;
  message.lease_id = lease_id_;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    message.stage = stage_;
    message.progress = progress_;
    while (!pending_.empty() && message.log.size() < kMaxLinesPerBeat) {
      message.log.push_back(std::move(pending_.front()));
      pending_.pop_front();
    }
  }
  try {
    const proto::HeartbeatReply reply = api.heartbeat(job_id_, message);
    if (reply.canceled && !canceled_.exchange(true))
      spdlog::info("job {}: canceled by the server", job_id_);
    std::lock_guard<std::mutex> lock(mutex_);
    transport_failures_ = 0;
    return true;
  } catch (const client::ApiCallError& e) {
    if (e.status() == 409) {
      if (!lease_lost_.exchange(true)) spdlog::warn("job {}: lease lost ({})", job_id_, e.what());
      return false;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    // Keep the lines for the next beat, in order.
    pending_.insert(pending_.begin(), std::make_move_iterator(message.log.begin()),
                    std::make_move_iterator(message.log.end()));
    if (transport_failures_++ % 10 == 0)
      spdlog::warn("job {}: heartbeat failed ({}); retrying", job_id_, e.what());
    return false;
  } catch (const std::exception& e) {
    spdlog::warn("job {}: heartbeat failed ({})", job_id_, e.what());
    return false;
  }
}

}  // namespace keel::worker
