#include "storage/pg_listener.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <pqxx/pqxx>
#include <sstream>

#include "storage/open_store.h"
#include "storage/pg_connection.h"

namespace keel::storage {

namespace {

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

class Receiver : public pqxx::notification_receiver {
 public:
  Receiver(pqxx::connection_base& connection, const PgListenerOptions& options)
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
  const PgListenerOptions& options_;
};

}  // namespace

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

PgListener::PgListener(PgListenerOptions options) : options_(std::move(options)) {
  thread_ = std::thread([this] { run(); });
}

PgListener::~PgListener() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

bool PgListener::wait_listening(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  return listening_.wait_for(lock, timeout, [this] { return connected_.load(); });
}

void PgListener::listen_once() {
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
  while (!stop_) connection.await_notification(0, 200'000);
}

void PgListener::run() {
  double backoff_s = options_.min_backoff_s;
  while (!stop_) {
    try {
      listen_once();
    } catch (const std::exception& error) {
      if (stop_) break;
      const bool was_connected = connected_.exchange(false);
      if (was_connected) backoff_s = options_.min_backoff_s;
      if (was_connected || backoff_s == options_.min_backoff_s)
        spdlog::warn("change feed: {}; reconnecting", error.what());
      const auto until =
          std::chrono::steady_clock::now() + std::chrono::duration<double>(backoff_s);
      while (!stop_ && std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      backoff_s = std::min(options_.max_backoff_s, backoff_s * 2);
      continue;
    }
  }
  connected_ = false;
}

}  // namespace keel::storage
