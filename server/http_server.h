// The socket side of keel-server: an Asio acceptor, `threads` io threads and one Beast
// session per connection (keep-alive). Each request is read header first; the route's body
// limit (HttpHandler::body_limit) is applied before the body is read. Every read has a
// deadline, so idle or stalled clients are dropped; file answers are streamed. With a
// certificate and key the same sessions run over TLS (Beast's OpenSSL stream).
// Beast stays out of this header (pimpl).
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "server/http_handler.h"

namespace keel::server {

struct ServerOptions {
  std::string address = "127.0.0.1";
  uint16_t port = 8080;                             // 0 = an ephemeral port (see port())
  int threads = 2;                                  // io threads
  uint32_t header_limit_bytes = 16 * 1024;          // larger headers -> 431
  std::chrono::milliseconds read_timeout{30'000};   // per read: header, each body piece
  std::chrono::milliseconds write_timeout{60'000};  // per write of a response piece
  std::chrono::milliseconds shutdown_grace{5'000};  // in-flight requests may finish
  // Open connections at most; beyond it new ones wait in the listen queue (0 = no limit).
  int max_connections = 4096;
  // Both set: HTTPS only (TLS 1.2+), PEM files. Both empty: plain HTTP.
  std::string tls_cert_file;
  std::string tls_key_file;
};

class HttpServer {
 public:
  HttpServer(HttpHandler& handler, ServerOptions options);
  ~HttpServer();  // stops
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Binds and listens (std::runtime_error naming the address on failure) and starts the
  // io threads. Returns at once.
  void start();
  uint16_t port() const;    // the bound port, valid after start()
  std::string url() const;  // "http[s]://<address>:<port>"

  // Graceful: stops accepting, closes idle connections, lets requests in flight finish
  // within shutdown_grace, then stops the io threads. Idempotent; blocks until done.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keel::server
