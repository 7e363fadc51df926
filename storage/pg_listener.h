// The change feed between replicas: a writing transaction sends its changes with
// pg_notify(kChangeChannel, payload); each replica keeps one dedicated connection that
// LISTENs on the channel (a thread of its own) and hands what it hears to its ChangeHub.
// When that connection breaks it reconnects with backoff; notifications sent meanwhile are
// lost, so after a reconnect it reports `on_reconnect` (the store then tells its listeners
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

inline constexpr const char* kChangeChannel = "keel_changes";
// PostgreSQL refuses payloads of 8000 bytes or more.
inline constexpr size_t kMaxNotifyPayloadBytes = 7900;

// Payloads for `changes` sent by the store `origin`: "origin\n" then one line per change,
// "kind|job_id|project|state" (ids, project names and states never hold '|' or '\n'),
// split so each payload stays under kMaxNotifyPayloadBytes.
std::vector<std::string> encode_changes(const std::string& origin,
                                        const std::vector<Change>& changes);
// The inverse; false for a payload that is not Keel's (ignored by listeners).
bool decode_changes(const std::string& payload, std::string& origin, std::vector<Change>& changes);

struct PgListenerOptions {
  std::string database_url;
  std::string origin;  // payloads from this origin are skipped (the store published them)
  std::function<void(const std::vector<Change>&)> deliver;
  std::function<void()> on_reconnect;  // after a reconnect (not the first connect)
  double min_backoff_s = 0.1;
  double max_backoff_s = 5.0;
};

class PgListener {
 public:
  explicit PgListener(PgListenerOptions options);  // starts the thread
  ~PgListener();                                   // stops it (within ~0.2 s)
  PgListener(const PgListener&) = delete;
  PgListener& operator=(const PgListener&) = delete;

  bool connected() const { return connected_.load(); }
  int connects() const { return connects_.load(); }  // successful connects so far
  // Waits until the first LISTEN is in place (true) or `timeout` passes (false). A store
  // waits for it before it is used, so a change another replica makes after this store
  // opened is never missed for want of a listener not yet listening.
  bool wait_listening(std::chrono::milliseconds timeout);

 private:
  void run();
  void listen_once();

  PgListenerOptions options_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> connected_{false};
  std::atomic<int> connects_{0};
  std::mutex mutex_;
  std::condition_variable listening_;
  std::thread thread_;
};

}  // namespace keel::storage
