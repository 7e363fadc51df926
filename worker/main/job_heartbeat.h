// The heartbeat of one leased job: a thread that every `period_s` sends the running stage,
// its progress and the log lines written since the last beat. The reply extends the lease
// and says whether the job was canceled; a 409 `lease_lost` means another worker owns it.
// Either makes should_stop() true, which the stages see at their next check_canceled().
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "client/api_client.h"

namespace keel::worker {

class JobHeartbeat {
 public:
  // `api` is used only by the heartbeat thread (ApiClient is not thread-safe).
  JobHeartbeat(client::ApiClient& api, std::string job_id, std::string lease_id, double period_s);
  ~JobHeartbeat();  // stops the thread
  JobHeartbeat(const JobHeartbeat&) = delete;
  JobHeartbeat& operator=(const JobHeartbeat&) = delete;

  void start();
  // Stops the thread after the beat in flight (if any). Idempotent.
  void stop();

  void set_stage(const std::string& stage);
  void set_progress(double progress);
  void log(const std::string& line);  // queued for the next beat

  bool canceled() const { return canceled_.load(); }
  bool lease_lost() const { return lease_lost_.load(); }

  // After stop(): sends the queued lines in one last beat on the caller's `api`. Returns
  // false (and logs why) when it could not be delivered; sets lease_lost on a 409.
  bool flush(client::ApiClient& api);

 private:
  void loop();
  // One beat on `api`; lines that could not be sent go back to the queue.
  bool beat(client::ApiClient& api);

  client::ApiClient& api_;
  const std::string job_id_;
  const std::string lease_id_;
  const double period_s_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::string stage_;
  double progress_ = 0.0;
  std::deque<std::string> pending_;
  int transport_failures_ = 0;

  std::atomic<bool> canceled_{false};
  std::atomic<bool> lease_lost_{false};
  std::thread thread_;
};

}  // namespace keel::worker
