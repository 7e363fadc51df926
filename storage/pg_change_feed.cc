#include "storage/pg_change_feed.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <memory>
#include <pqxx/pqxx>
#include <sstream>

#include "storage/open_store.h"

namespace keel::storage {

namespace {

constexpr const char* kChangeChannel = "keel_changes";
// PostgreSQL refuses payloads of 8000 bytes or more.
constexpr size_t kMaxNotifyPayloadBytes = 7900;
constexpr double kMinBackoffS = 0.1, kMaxBackoffS = 5.0;  // between LISTEN reconnects

// A payload is "origin\n" then one line per change, "kind|job_id|project|state" (ids, project
// names and states never hold '|' or '\n').
constexpr char kKindJob = 'j';
constexpr char kKindLog = 'l';

std::string encode_change(const Change& change) {
  return std::string(1, change.kind == Change::Kind::kLog ? kKindLog : kKindJob) + "|" +
         change.job_id + "|" + change.project + "|" + proto::to_string(change.state);
}

bool decode_change(const std::string& line, Change& change) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  std::string field;
  while (std::getline(in, field, '|')) fields.push_back(field);
  if (line.back() == '|') fields.emplace_back();
  if (fields.size() != 4 || fields[0].size() != 1) return false;
  if (fields[0][0] == kKindJob)
    change.kind = Change::Kind::kJob;
  else if (fields[0][0] == kKindLog)
    change.kind = Change::Kind::kLog;
  else
    return false;
  change.job_id = fields[1];
  change.project = fields[2];
  try {
    change.state = proto::job_state_from_string(fields[3]);
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

// The payloads for `changes`, split so each stays under kMaxNotifyPayloadBytes.
std::vector<std::string> encode_changes(const std::string& origin,
                                        const std::vector<Change>& changes) {
  std::vector<std::string> payloads;
  std::string payload = origin;
  bool holds_change = false;
  for (const Change& change : changes) {
    const std::string line = encode_change(change);
    if (holds_change && payload.size() + 1 + line.size() > kMaxNotifyPayloadBytes) {
      payloads.push_back(std::move(payload));
      payload = origin;
    }
    payload += "\n" + line;
    holds_change = true;
  }
  if (holds_change) payloads.push_back(std::move(payload));
  return payloads;
}

// The inverse; false for a payload that is not Keel's (ignored).
bool decode_changes(const std::string& payload, std::string& origin, std::vector<Change>& changes) {
  std::stringstream in(payload);
  if (!std::getline(in, origin) || origin.empty()) return false;
  std::string line;
  while (std::getline(in, line)) {
    Change change;
    if (line.empty() || !decode_change(line, change)) return false;
    changes.push_back(std::move(change));
  }
  return true;
}

// The same change twice in one batch is said once (listeners re-read what they need).
void drop_repeats(std::vector<Change>& changes) {
  std::vector<Change> kept;
  for (Change& change : changes) {
    bool seen = false;
    for (const Change& k : kept)
      seen |= k.kind == change.kind && k.job_id == change.job_id && k.state == change.state &&
              k.project == change.project;
    if (!seen) kept.push_back(std::move(change));
  }
  changes.swap(kept);
}

class Receiver : public pqxx::notification_receiver {
 public:
  Receiver(pqxx::connection_base& connection, const PgChangeFeedOptions& options)
      : pqxx::notification_receiver(connection, kChangeChannel), options_(options) {}

  void operator()(const std::string& payload, int) override {
    std::string origin;
    std::vector<Change> changes;
    if (!decode_changes(payload, origin, changes)) {
      spdlog::warn("change feed: ignoring a notification that is not Keel's");
      return;
    }
    if (origin == options_.origin || changes.empty()) return;
    options_.deliver(changes);
  }

 private:
  const PgChangeFeedOptions& options_;
};

}  // namespace

PgChangeFeed::PgChangeFeed(PgChangeFeedOptions options) : options_(std::move(options)) {
  sender_ = std::thread([this] { notify_loop(); });
  listener_ = std::thread([this] { listen_loop(); });
}

PgChangeFeed::~PgChangeFeed() {
  stop_listening_ = true;
  listener_.join();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_sending_ = true;
  }
  queued_.notify_all();
  sender_.join();
}

// --- sending ---

void PgChangeFeed::send(const std::vector<Change>& changes) {
  if (changes.empty()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_.insert(pending_.end(), changes.begin(), changes.end());
  }
  queued_.notify_one();
}

void PgChangeFeed::notify_loop() {
  std::unique_ptr<pqxx::connection> connection;
  auto backoff = std::chrono::milliseconds(100);
  for (;;) {
    std::vector<Change> batch;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      queued_.wait(lock, [&] { return stop_sending_ || !pending_.empty(); });
      if (pending_.empty()) return;  // stopping with nothing left to send
      batch.swap(pending_);
    }
    drop_repeats(batch);
    try {
      if (!connection) {
        connection = std::make_unique<pqxx::connection>(options_.database_url);
        pqxx::nontransaction setup(*connection);
        // This connection writes no data: its commits need not wait for the WAL flush.
        setup.exec("SET synchronous_commit = off");
      }
      pqxx::nontransaction work(*connection);  // autocommit: one statement, one round trip
      for (const std::string& payload : encode_changes(options_.origin, batch))
        work.exec_params("SELECT pg_notify($1, $2)", kChangeChannel, payload);
      backoff = std::chrono::milliseconds(100);
    } catch (const std::exception& error) {
      // The batch is lost to other replicas (their fallback tick covers it); reconnect.
      spdlog::warn("change feed: cannot notify other replicas: {}", error.what());
      connection.reset();
      std::unique_lock<std::mutex> lock(mutex_);
      if (queued_.wait_for(lock, backoff, [&] { return stop_sending_; })) return;
      backoff = std::min(backoff * 2, std::chrono::milliseconds(5000));
    }
  }
}

// --- listening ---

bool PgChangeFeed::wait_listening(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  return listening_.wait_for(lock, timeout, [this] { return connected_.load(); });
}

void PgChangeFeed::listen_once() {
  pqxx::connection connection(options_.database_url);
  Receiver receiver(connection, options_);
  connection.get_notifs();  // sends the LISTEN now, so nothing after this point is missed
  {
    std::lock_guard<std::mutex> lock(mutex_);
    connected_ = true;
  }
  listening_.notify_all();
  if (connects_++ > 0) {
    spdlog::info("change feed: listening again on {}", redact_database_url(options_.database_url));
    if (options_.on_reconnect) options_.on_reconnect();
  }
  while (!stop_listening_) connection.await_notification(0, 200'000);
}

void PgChangeFeed::listen_loop() {
  double backoff_s = kMinBackoffS;
  while (!stop_listening_) {
    try {
      listen_once();
    } catch (const std::exception& error) {
      if (stop_listening_) break;
      const bool was_connected = connected_.exchange(false);
      if (was_connected) backoff_s = kMinBackoffS;
      if (was_connected || backoff_s == kMinBackoffS)
        spdlog::warn("change feed: {}; reconnecting", error.what());
      const auto until =
          std::chrono::steady_clock::now() + std::chrono::duration<double>(backoff_s);
      while (!stop_listening_ && std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      backoff_s = std::min(kMaxBackoffS, backoff_s * 2);
    }
  }
  connected_ = false;
}

}  // namespace keel::storage
