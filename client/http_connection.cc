#include "client/http_connection.h"

#include <sys/socket.h>

#include <boost/asio/connect.hpp>

#include <cerrno>

namespace keel::client {

namespace net = boost::asio;
namespace beast = boost::beast;

namespace {
constexpr size_t kReadChunkBytes = 64 << 10;
}  // namespace

HttpConnection::HttpConnection(BaseUrl url, double timeout_s, TransferStats& stats)
    : url_(std::move(url)), timeout_s_(timeout_s), stats_(stats), stream_(ioc_) {}

std::string HttpConnection::describe(const std::string& method, const std::string& target) const {
  return method + " http://" + url_.host + ":" + url_.port + target;
}

std::chrono::steady_clock::duration HttpConnection::timeout() const {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(timeout_s_));
}

bool HttpConnection::peer_closed() const {
  // An idle kept-alive socket has nothing to read; EOF or stray bytes mean it is unusable.
  char byte;
  const int fd = const_cast<beast::tcp_stream&>(stream_).socket().native_handle();
  const ssize_t n = ::recv(fd, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
  if (n < 0) return errno != EAGAIN && errno != EWOULDBLOCK;
  return true;
}

bool HttpConnection::ensure_open(const std::string& what) {
  if (open_ && !peer_closed()) return true;
  if (open_) close();
  if (endpoints_.empty()) {
    net::ip::tcp::resolver resolver(ioc_);
    beast::error_code ec;
    endpoints_ = resolver.resolve(url_.host, url_.port, ec);
    if (ec)
      throw ApiCallError(0, "transport",
                         what + ": cannot resolve " + url_.host + ": " + ec.message());
  }
  stream_.expires_after(timeout());
  beast::error_code result = net::error::would_block;
  stream_.async_connect(endpoints_, [&result](beast::error_code ec, const auto&) { result = ec; });
  ioc_.restart();
  ioc_.run();
  if (result) {
    stream_.socket().close();
    throw ApiCallError(0, "transport", what + ": cannot connect: " + result.message());
  }
  stream_.socket().set_option(net::ip::tcp::no_delay(true));
  buffer_.clear();
  // Beast reads at most the buffer's free capacity (>= 512 B) per call: room for 64 KiB
  // keeps large bodies at one system call per 64 KiB instead of per 512 B.
  buffer_.reserve(kReadChunkBytes);
  open_ = true;
  ++stats_.connections;
  return false;
}

void HttpConnection::close() {
  beast::error_code ignored;
  stream_.socket().shutdown(net::ip::tcp::socket::shutdown_both, ignored);
  stream_.socket().close(ignored);
  buffer_.clear();
  open_ = false;
}

bool is_stale_connection_error(const beast::error_code& ec) {
  return ec == http::error::end_of_stream || ec == net::error::eof ||
         ec == net::error::connection_reset || ec == net::error::broken_pipe ||
         ec == net::error::connection_aborted;
}

bool is_idempotent(http::verb verb) {
  return verb == http::verb::get || verb == http::verb::head || verb == http::verb::put ||
         verb == http::verb::delete_ || verb == http::verb::options;
}

}  // namespace keel::client
