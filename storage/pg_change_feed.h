// The change feed between replicas on one PostgreSQL database. A replica sends the changes
// it committed with pg_notify(kChangeChannel, payload) from a thread of its own, after the
// commit and in batches; each replica keeps one dedicated connection that LISTENs on the
// channel (another thread) and hands what it hears from the others to `deliver`.
//
// Why not pg_notify inside the writing transaction: PostgreSQL serializes every notifying
// commit behind one lock held across the commit's WAL flush, so with fsync at ~7 ms (this
// project's cloud disks) all notifying writes together could not pass ~140/s, far below the
// queue's 500 leases/s (tests/bench/pg_queue_bench measures both). Here the notifying
// transaction is the feed's own, with synchronous_commit off (it writes no data), and one
// notification carries every change committed meanwhile. A change whose replica dies
// between its commit and the send is not heard elsewhere: listeners re-read on their
// fallback tick (the long poll's 2 s), as after a lost LISTEN connection.
//
// When the LISTEN connection breaks it reconnects with backoff; notifications sent meanwhile
// are lost, so after a reconnect it calls `on_reconnect` (the store then tells its listeners
// to re-read) and the long poll's fallback tick covers the rest.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "storage/store.h"

namespace keel::storage {

struct PgChangeFeedOptions {
  std::string database_url;
  std::string origin;  // this store's id in its payloads: its own are not delivered back
  std::function<void(const std::vector<Change>&)> deliver;
  std::function<void()> on_reconnect;  // after a reconnect (not the first connect)
};

class PgChangeFeed {
 public:
  explicit PgChangeFeed(PgChangeFeedOptions options);  // starts both threads
  // Stops listening (within ~0.2 s), then sends what is queued (bounded wait) and stops.
  ~PgChangeFeed();
  PgChangeFeed(const PgChangeFeed&) = delete;
  PgChangeFeed& operator=(const PgChangeFeed&) = delete;

  // Queues committed changes for the other replicas; returns at once.
  void send(const std::vector<Change>& changes);
  // Waits until the first LISTEN is in place (true) or `timeout` passes (false). A store
  // waits for it before it is used, so a change another replica makes after this store
  // opened is never missed for want of a listener not yet listening.
  bool wait_listening(std::chrono::milliseconds timeout);

 private:
  void notify_loop();
  void listen_loop();
  void listen_once();

  PgChangeFeedOptions options_;
  std::mutex mutex_;
  std::condition_variable queued_, listening_;
  std::vector<Change> pending_;  // guarded by mutex_
  bool stop_sending_ = false;    // guarded by mutex_
  std::atomic<bool> stop_listening_{false};
  std::atomic<bool> connected_{false};
  int connects_ = 0;  // successful LISTEN connects so far (the listening thread's)
  std::thread sender_, listener_;
};

}  // namespace keel::storage
