// GET /v1/events: the store's change feed as server-sent events (docs/api.md "Live events
// and the queue"), limited to what the token may read. Changes are coalesced per job
// between two writes, so a fast-moving job costs one event per write, not one per change.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include "proto/auth.h"
#include "server/http_types.h"
#include "storage/store.h"

namespace keel::server {

struct JobEventsOptions {
  std::string job_id;  // "" = every job the token reaches
  std::chrono::milliseconds ping_interval{15'000};
  std::function<int64_t()> now_ms;  // wall clock for the hello event
};

class JobEvents : public EventStream {
 public:
  JobEvents(storage::Store& store, proto::TokenInfo reader, JobEventsOptions options);
  ~JobEvents() override;

  void start(std::function<void()> wake) override;
  std::string take(bool final, bool& ended) override;
  std::chrono::milliseconds tick() const override;

 private:
  void on_change(const storage::Change& change);
  std::string job_event(const std::string& job_id);

  storage::Store& store_;
  proto::TokenInfo reader_;
  JobEventsOptions options_;
  std::function<void()> wake_;
  std::unique_ptr<storage::Subscription> subscription_;

  std::mutex mutex_;
  std::set<std::string> changed_jobs_;  // guarded by mutex_
  std::set<std::string> logged_jobs_;   // guarded by mutex_
  bool reload_ = false;                 // guarded by mutex_: many jobs changed at once
  bool hello_sent_ = false;
  std::chrono::steady_clock::time_point last_sent_;
};

// One server-sent event: "event: <type>\ndata: <data>\n\n" (data must be one line).
std::string sse_event(const std::string& type, const std::string& data);

}  // namespace keel::server
