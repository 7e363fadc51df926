#include "client/http_connection.h"

#include <sys/socket.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ssl/host_name_verification.hpp>
#include <openssl/ssl.h>
#include <openssl/x509.h>

#include <cerrno>

namespace keel::client {

namespace net = boost::asio;
namespace beast = boost::beast;

namespace {
constexpr size_t kReadChunkBytes = 64 << 10;
}  // namespace

HttpConnection::HttpConnection(BaseUrl url, double timeout_s, TransferStats& stats,
                               const std::string& ca_file)
    : url_(std::move(url)), timeout_s_(timeout_s), stats_(stats), stream_(ioc_) {
  if (!url_.tls) return;
  tls_context_ = std::make_unique<net::ssl::context>(net::ssl::context::tls_client);
  SSL_CTX_set_min_proto_version(tls_context_->native_handle(), TLS1_2_VERSION);
  beast::error_code ec;
  if (ca_file.empty())
    tls_context_->set_default_verify_paths(ec);
  else
    tls_context_->load_verify_file(ca_file, ec);
  if (ec)
    throw ApiCallError(0, "transport",
                       (ca_file.empty() ? std::string("the system's CA certificates")
                                        : "--ca-file " + ca_file) +
                           ": cannot load: " + ec.message());
  tls_context_->set_verify_mode(net::ssl::verify_peer);
}

std::string HttpConnection::describe(const std::string& method, const std::string& target) const {
  return method + " " + url_.scheme() + "://" + url_.host + ":" + url_.port + target;
}

void HttpConnection::handshake(const std::string& what) {
  tls_.emplace(stream_, *tls_context_);
  SSL* ssl = tls_->native_handle();
  // The name the certificate must carry (an IP address is checked as one), and SNI for a
  // name (RFC 6066 allows no IP literals there).
  tls_->set_verify_callback(net::ssl::host_name_verification(url_.host));
  beast::error_code ec;
  net::ip::make_address(url_.host, ec);
  if (ec && !SSL_set_tlsext_host_name(ssl, url_.host.c_str())) {
    close();
    throw ApiCallError(0, "transport", what + ": cannot set the TLS server name " + url_.host);
  }
  stream_.expires_after(timeout());
  beast::error_code result = net::error::would_block;
  tls_->async_handshake(net::ssl::stream_base::client, [&result](beast::error_code e) { result = e; });
  ioc_.restart();
  ioc_.run();
  if (result) {
    std::string detail = result.message();
    const long verify = SSL_get_verify_result(ssl);
    if (verify != X509_V_OK)
      detail = std::string("the server's certificate is not trusted: ") +
               X509_verify_cert_error_string(verify) + " (checked against " + url_.host +
               " and the CA certificates; give --ca-file for a private CA)";
    close();
    throw ApiCallError(0, "transport", what + ": TLS handshake failed: " + detail);
  }
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
  if (url_.tls) handshake(what);
  buffer_.clear();
  // Beast reads at most the buffer's free capacity (>= 512 B) per call: room for 64 KiB
  // keeps large bodies at one system call per 64 KiB instead of per 512 B.
  buffer_.reserve(kReadChunkBytes);
  open_ = true;
  ++stats_.connections;
  return false;
}

void HttpConnection::close() {
  tls_.reset();
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
