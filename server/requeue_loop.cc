#include "server/requeue_loop.h"

#include <spdlog/spdlog.h>

namespace keel::server {

RequeueLoop::RequeueLoop(storage::Store& store, std::chrono::milliseconds interval)
    : store_(store), interval_(interval) {
  thread_ = std::thread([this] { run(); });
}

RequeueLoop::~RequeueLoop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  stopping_.notify_all();
  thread_.join();
}

int RequeueLoop::requeued() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return requeued_;
}

void RequeueLoop::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopping_.wait_for(lock, interval_, [&] { return stop_; })) {
    lock.unlock();
    int count = 0;
    try {
      count = store_.requeue_expired_leases();
      if (count > 0) spdlog::info("requeued {} job(s) whose lease expired", count);
    } catch (const std::exception& error) {
      // The database may be away for a while: the next round tries again.
      spdlog::warn("requeueing expired leases: {}", error.what());
    }
    lock.lock();
    requeued_ += count;
  }
}

}  // namespace keel::server
