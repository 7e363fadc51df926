// The server's own small HTTP request/response types. The pure handler (http_handler.h and
// the route files) works on these instead of Beast's message types so that it, its tests and
// everything that includes it compile without Beast/Asio (the heavy headers stay in the
// socket-side files: http_server.cc, http_session.cc and file_region_body.h).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace keel::server {

// Header fields in arrival order; names compare case-insensitively.
class Headers {
 public:
  void set(std::string name, std::string value);  // replaces an existing field
  void add(std::string name, std::string value);  // keeps existing fields
  // The first value of `name`, or nullopt.
  std::optional<std::string> get(std::string_view name) const;
  bool has(std::string_view name) const { return get(name).has_value(); }
  const std::vector<std::pair<std::string, std::string>>& fields() const { return fields_; }

 private:
  std::vector<std::pair<std::string, std::string>> fields_;
};

bool iequals(std::string_view a, std::string_view b);

struct Request {
  std::string method;  // "GET", "PUT", ...
  std::string target;  // origin-form: "/v1/jobs?state=queued"
  Headers headers;
  std::string body;
};

// Bytes [offset, offset + length) of a file, streamed by the socket side.
struct FileRegion {
  std::filesystem::path path;
  uint64_t offset = 0;
  uint64_t length = 0;
};

struct Response;

// Answers that are not complete when the route returns. The socket side drives them on the
// connection's strand: start() once, then poll()/take() whenever `wake` is called (from any
// thread, any number of times), every tick(), and (PendingResponse) at deadline(). Tests
// drive them the same way without sockets.
//
// A long poll (POST /v1/worker/lease with wait_seconds): the answer is one whole Response,
// ready later.
class PendingResponse {
 public:
  virtual ~PendingResponse() = default;
  virtual void start(std::function<void()> wake) = 0;
  // The answer when ready, else nullopt. With `final` (the deadline passed, or the server is
  // stopping) it must answer.
  virtual std::optional<Response> poll(bool final) = 0;
  virtual std::chrono::steady_clock::time_point deadline() const = 0;
  virtual std::chrono::milliseconds tick() const { return std::chrono::seconds(2); }
};

// A body that keeps coming (server-sent events): the socket side sends the Response's status
// and headers with chunked transfer coding, then each piece take() gives.
class EventStream {
 public:
  virtual ~EventStream() = default;
  virtual void start(std::function<void()> wake) = 0;
  // The bytes to send now ("" = nothing yet); sets `ended` when the stream is over. With
  // `final` (the server is stopping) the stream must end.
  virtual std::string take(bool final, bool& ended) = 0;
  virtual std::chrono::milliseconds tick() const { return std::chrono::seconds(5); }
};

struct Response {
  int status = 200;
  Headers headers;
  std::string body;                // used when `file` is empty
  std::optional<FileRegion> file;  // a file region to stream instead of `body`
  std::shared_ptr<PendingResponse> pending;  // set: the real answer comes later
  std::shared_ptr<EventStream> stream;       // set: status + headers now, body as it comes
};

}  // namespace keel::server
