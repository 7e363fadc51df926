// Keel's HTTP API v1 (docs/api.md) as a pure function of a request: no sockets, no Beast.
// The socket side (http_server.h) reads a Request, calls handle() and writes the Response;
// tests call handle() directly against a real Store.
//
// handle() never throws: route errors become {"error": {"code", "message"}} answers
// (ContractError -> 400 invalid_field, NotFound -> 404, Conflict -> 409, Invalid -> 400,
// StorageFull or ENOSPC -> 507 insufficient_storage, anything unexpected -> 500 internal)
// and the handler stays usable.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "proto/auth.h"
#include "server/http_types.h"
#include "server/rate_limiter.h"
#include "server/request_counters.h"
#include "server/static_files.h"
#include "storage/store.h"

namespace keel::server {

struct HandlerOptions {
  uint64_t max_chunk_bytes = 64ull << 20;  // PUT /v1/uploads/{id} body limit
  uint64_t max_json_bytes = 1ull << 20;    // every other body
  std::string version = "0.1.0";           // shown by /healthz
  std::function<int()> workers_alive;      // for /metrics; empty = 0
  std::shared_ptr<const StaticFiles> web;  // the dashboard at "/"; null = none (404)
  std::function<int64_t()> wall_clock_ms;  // for event timestamps; empty = the system clock
  // Storage limits: uploads and chunks that would leave less than `min_free_bytes` free on
  // the data folder's disk are refused with 507 (free_bytes empty = no check).
  int64_t min_free_bytes = 0;
  std::function<int64_t()> free_bytes;
  // Requests per API token (429 rate_limited with Retry-After beyond it); rate 0 = none.
  RateLimit rate_limit;
  std::function<double()> monotonic_s;  // for the rate limit; empty = steady_clock
};

class HttpHandler {
 public:
  HttpHandler(storage::Store& store, HandlerOptions options = {});
  ~HttpHandler();
  HttpHandler(const HttpHandler&) = delete;
  HttpHandler& operator=(const HttpHandler&) = delete;

  // Thread-safe; never throws.
  Response handle(const Request& request);

  // The largest body the route of (method, target) accepts, known once the header is read.
  uint64_t body_limit(std::string_view method, std::string_view target) const;

  // Counts an answer the socket side made itself (413, 431, ...) for /metrics.
  void count_response(int status) { counters_.count(status); }
  const RequestCounters& counters() const { return counters_; }
  const HandlerOptions& options() const { return options_; }

 private:
  Response dispatch(const Request& request);
  // The bearer token's record, or nullopt when missing, unknown, expired or revoked.
  std::optional<proto::TokenInfo> authorized(const Request& request);

  storage::Store& store_;
  HandlerOptions options_;
  RequestCounters counters_;
  RateLimiter limiter_;
};

}  // namespace keel::server
