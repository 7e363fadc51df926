// One kept-alive HTTP/1.1 connection to a Keel server, driven synchronously: every
// operation is an async Beast operation run to completion on a private io_context, which
// is what makes `tcp_stream::expires_after` deadlines apply (Beast ignores them for
// blocking calls). Internal to client/: ApiClient is the public face.
//
// https URLs speak TLS 1.2+ over the same TCP stream (Beast's OpenSSL stream) and always
// verify the server: its chain against the system's CAs or `ca_file`, and its name against
// the URL's host. There is no way to skip that.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>

#include <chrono>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "client/api_client.h"
#include "client/http_url.h"

namespace keel::client {

namespace http = boost::beast::http;

// "No body limit". Beast 1.74's parser compares Content-Length against an empty optional
// as if the limit were below every length, so body_limit(boost::none) rejects every body
// with a Content-Length; the largest value is the working spelling of "none".
inline constexpr std::uint64_t kNoBodyLimit = std::numeric_limits<std::uint64_t>::max();

class HttpConnection {
 public:
  // `ca_file`: PEM CA certificates to trust for https instead of the system's ("" = system).
  HttpConnection(BaseUrl url, double timeout_s, TransferStats& stats, const std::string& ca_file = "");

  const BaseUrl& url() const { return url_; }
  // "METHOD http://host:port/target", for error messages.
  std::string describe(const std::string& method, const std::string& target) const;

  // Writes `request` and reads the whole answer. A kept-alive connection that the server
  // closed while idle is replaced transparently: noticed before sending (any method), or
  // by an immediate EOF/reset on the answer (idempotent methods are then sent once more).
  // Throws ApiCallError(0, "transport", ...) otherwise.
  template <class Body>
  http::response<http::string_body> exchange(http::request<Body>& request);

  // Opens the connection when needed; returns true when an open connection was reused.
  bool ensure_open(const std::string& what);
  // Async-with-deadline versions of Beast's write/read; errors come back, never thrown.
  template <class Body>
  boost::beast::error_code write(http::request<Body>& request);
  template <class Parser>
  boost::beast::error_code read_header(Parser& parser);
  template <class Parser>
  boost::beast::error_code read_some(Parser& parser);
  template <class Parser>
  boost::beast::error_code read(Parser& parser);
  void close();

 private:
  using TlsStream = boost::beast::ssl_stream<boost::beast::tcp_stream&>;

  template <class Start>
  boost::beast::error_code run(Start&& start);
  // Calls f(stream) with the TLS stream when there is one, else the TCP stream.
  template <class F>
  auto with_stream(F&& f) {
    if (tls_) return f(*tls_);
    return f(stream_);
  }
  void handshake(const std::string& what);
  bool peer_closed() const;
  std::chrono::steady_clock::duration timeout() const;

  BaseUrl url_;
  double timeout_s_;
  TransferStats& stats_;
  boost::asio::io_context ioc_;
  boost::beast::tcp_stream stream_;
  std::unique_ptr<boost::asio::ssl::context> tls_context_;  // set for https
  std::optional<TlsStream> tls_;                            // per connection, over stream_
  boost::beast::flat_buffer buffer_;
  boost::asio::ip::tcp::resolver::results_type endpoints_;
  bool open_ = false;
};

// True for the errors a server's idle close produces on the next request.
bool is_stale_connection_error(const boost::beast::error_code& ec);
// GET, HEAD, PUT, DELETE, OPTIONS (RFC 9110 section 9.2.2).
bool is_idempotent(http::verb verb);

template <class Start>
boost::beast::error_code HttpConnection::run(Start&& start) {
  boost::beast::error_code result = boost::asio::error::would_block;
  start([&result](boost::beast::error_code ec, std::size_t) { result = ec; });
  ioc_.restart();
  ioc_.run();
  if (result == boost::beast::error::timeout) open_ = false;  // tcp_stream closed it
  return result;
}

template <class Body>
boost::beast::error_code HttpConnection::write(http::request<Body>& request) {
  stream_.expires_after(timeout());
  return run([&](auto handler) {
    with_stream([&](auto& stream) { http::async_write(stream, request, std::move(handler)); });
  });
}

template <class Parser>
boost::beast::error_code HttpConnection::read_header(Parser& parser) {
  stream_.expires_after(timeout());
  return run([&](auto handler) {
    with_stream(
        [&](auto& stream) { http::async_read_header(stream, buffer_, parser, std::move(handler)); });
  });
}

template <class Parser>
boost::beast::error_code HttpConnection::read_some(Parser& parser) {
  stream_.expires_after(timeout());
  return run([&](auto handler) {
    with_stream(
        [&](auto& stream) { http::async_read_some(stream, buffer_, parser, std::move(handler)); });
  });
}

template <class Parser>
boost::beast::error_code HttpConnection::read(Parser& parser) {
  stream_.expires_after(timeout());
  return run([&](auto handler) {
    with_stream([&](auto& stream) { http::async_read(stream, buffer_, parser, std::move(handler)); });
  });
}

template <class Body>
http::response<http::string_body> HttpConnection::exchange(http::request<Body>& request) {
  const std::string what =
      describe(std::string(request.method_string()), std::string(request.target()));
  for (int attempt = 0;; ++attempt) {
    const bool reused = ensure_open(what);
    http::response_parser<http::string_body> parser;
    parser.body_limit(kNoBodyLimit);
    parser.skip(request.method() == http::verb::head);
    boost::beast::error_code ec = write(request);
    if (!ec) ec = read(parser);
    if (!ec) {
      http::response<http::string_body> response = parser.release();
      if (!response.keep_alive()) close();
      return response;
    }
    close();
    // Only idempotent requests are sent twice: a POST may have been processed already.
    // (An idle close noticed before sending is handled by ensure_open for every method.)
    if (reused && attempt == 0 && is_stale_connection_error(ec) && is_idempotent(request.method()))
      continue;
    throw ApiCallError(0, "transport", what + ": " + ec.message());
  }
}

}  // namespace keel::client
