// Requeues expired leases every interval (Store::requeue_expired_leases), on a thread of its
// own. Every replica runs one: the statement is safe to run anywhere at any time, so a job
// whose worker died is queued again within about one interval of its lease's expiry even
// when no worker asks for a lease (a lease also requeues first).
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "storage/store.h"

namespace keel::server {

class RequeueLoop {
 public:
  RequeueLoop(storage::Store& store, std::chrono::milliseconds interval);
  ~RequeueLoop();  // stops the thread (waits for a requeue in progress)
  RequeueLoop(const RequeueLoop&) = delete;
  RequeueLoop& operator=(const RequeueLoop&) = delete;

  int requeued() const;  // jobs this loop requeued (or failed) so far

 private:
  void run();

  storage::Store& store_;
  std::chrono::milliseconds interval_;
  mutable std::mutex mutex_;
  std::condition_variable stopping_;
  bool stop_ = false;  // guarded by mutex_
  int requeued_ = 0;   // guarded by mutex_
  std::thread thread_;
};

}  // namespace keel::server
