// POST /v1/worker/lease with wait_seconds > 0: a long poll. The waiter subscribes to the
// store's change feed before its first try, so a job queued at any moment (on any replica)
// wakes it; a fallback try every tick() covers notifications lost on a reconnect.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>

#include "proto/worker_protocol.h"
#include "server/http_types.h"
#include "storage/store.h"

namespace keel::server {

class LeaseWait : public PendingResponse {
 public:
  LeaseWait(storage::Store& store, proto::LeaseRequest request,
            std::chrono::steady_clock::time_point deadline);
  ~LeaseWait() override;

  void start(std::function<void()> wake) override;
  std::optional<Response> poll(bool final) override;
  std::chrono::steady_clock::time_point deadline() const override { return deadline_; }

 private:
  storage::Store& store_;
  proto::LeaseRequest request_;
  std::chrono::steady_clock::time_point deadline_;
  std::unique_ptr<storage::Subscription> subscription_;
};

// The answer to one lease attempt: 200 with the lease, or 204 when nothing is queued.
std::optional<Response> try_lease(storage::Store& store, const proto::LeaseRequest& request);

}  // namespace keel::server
