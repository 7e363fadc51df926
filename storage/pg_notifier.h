// Sends this replica's committed changes to the other replicas (pg_notify on kChangeChannel),
// from a thread of its own, after the commit and in batches.
//
// Why not pg_notify inside the writing transaction: PostgreSQL serializes every notifying
// commit behind one lock held across the commit's WAL flush, so with fsync at ~7 ms (this
// project's cloud disks) all notifying writes together could not pass ~140/s, far below the
// queue's 500 leases/s (tests/bench/pg_queue_bench measures both). Here the notifying
// transaction is the notifier's own, with synchronous_commit off (it writes no data), and
// one notification carries every change committed meanwhile. A change whose replica dies
// between its commit and the send is not heard elsewhere: listeners re-read on their
// fallback tick (the long poll's 2 s), as after a lost LISTEN connection.
#pragma once

#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "storage/store.h"

namespace keel::storage {

class PgNotifier {
 public:
  PgNotifier(std::string database_url, std::string origin);  // starts the thread
  ~PgNotifier();  // sends what is queued (bounded wait), then stops
  PgNotifier(const PgNotifier&) = delete;
  PgNotifier& operator=(const PgNotifier&) = delete;

  // Queues committed changes; returns at once.
  void send(const std::vector<Change>& changes);

 private:
  void run();

  std::string database_url_;
  std::string origin_;
  std::mutex mutex_;
  std::condition_variable queued_;
  std::vector<Change> pending_;  // guarded by mutex_
  bool stop_ = false;            // guarded by mutex_
  std::thread thread_;
};

}  // namespace keel::storage
