#include "server/http_server.h"

#include <openssl/ssl.h>
#include <spdlog/spdlog.h>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>

#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "server/http_session.h"

namespace keel::server {

// A TLS context for a server: the certificate chain and key in PEM, TLS 1.2 or newer.
std::unique_ptr<net::ssl::context> make_tls_context(const ServerOptions& options) {
  auto context = std::make_unique<net::ssl::context>(net::ssl::context::tls_server);
  context->set_options(net::ssl::context::default_workarounds | net::ssl::context::no_sslv2 |
                       net::ssl::context::no_sslv3 | net::ssl::context::no_tlsv1 |
                       net::ssl::context::no_tlsv1_1 | net::ssl::context::single_dh_use);
  SSL_CTX_set_min_proto_version(context->native_handle(), TLS1_2_VERSION);
  error_code ec;
  context->use_certificate_chain_file(options.tls_cert_file, ec);
  if (ec)
    throw std::runtime_error("--tls-cert " + options.tls_cert_file +
                             ": cannot load a PEM certificate chain: " + ec.message());
  context->use_private_key_file(options.tls_key_file, net::ssl::context::pem, ec);
  if (ec)
    throw std::runtime_error("--tls-key " + options.tls_key_file +
                             ": cannot load a PEM private key: " + ec.message());
  if (SSL_CTX_check_private_key(context->native_handle()) != 1)
    throw std::runtime_error("--tls-key " + options.tls_key_file +
                             " does not match the certificate in " + options.tls_cert_file);
  return context;
}

struct HttpServer::Impl {
  // Declared before io_context: sessions destroyed with the io_context still unregister.
  ServerCore core;
  std::unique_ptr<net::ssl::context> tls;  // set: HTTPS
  net::io_context io_context;
  tcp::acceptor acceptor;
  net::steady_timer accept_retry;
  std::vector<std::thread> threads;
  uint16_t port = 0;
  bool started = false;
  bool stopped = false;
  std::mutex stop_mutex;

  Impl(HttpHandler& handler, ServerOptions options)
      : core(handler, std::move(options)),
        io_context(core.options.threads),
        acceptor(net::make_strand(io_context)),
        accept_retry(acceptor.get_executor()) {}

  void accept() {
    acceptor.async_accept(net::make_strand(io_context), [this](error_code ec, tcp::socket socket) {
      if (ec == net::error::operation_aborted || !acceptor.is_open()) return;
      if (ec) {
        // Typically EMFILE: wait a little rather than spin.
        spdlog::warn("accept failed: {}; retrying in 100 ms", ec.message());
        accept_retry.expires_after(std::chrono::milliseconds(100));
        accept_retry.async_wait([this](error_code wait_ec) {
          if (!wait_ec) accept();
        });
        return;
      }
      error_code ignored;
      socket.set_option(tcp::no_delay(true), ignored);
      start_session(core, std::move(socket), tls.get());
      // At max_connections the next connections wait in the kernel's listen queue until a
      // session ends (it calls resume_accept), rather than being accepted and starved.
      {
        std::lock_guard<std::mutex> lock(core.sessions_mutex);
        if (core.options.max_connections > 0 &&
            core.sessions.size() >= static_cast<size_t>(core.options.max_connections)) {
          core.resume_accept = [this] { net::post(acceptor.get_executor(), [this] { accept(); }); };
          return;
        }
      }
      accept();
    });
  }
};

HttpServer::HttpServer(HttpHandler& handler, ServerOptions options)
    : impl_(std::make_unique<Impl>(handler, std::move(options))) {}

HttpServer::~HttpServer() { stop(); }

void HttpServer::start() {
  auto& impl = *impl_;
  if (impl.started) throw std::logic_error("HttpServer::start called twice");
  const auto& options = impl.core.options;
  error_code ec;
  const auto address = net::ip::make_address(options.address, ec);
  if (ec) throw std::runtime_error("listen address '" + options.address + "': " + ec.message());
  const tcp::endpoint endpoint(address, options.port);
  const std::string where = options.address + ":" + std::to_string(options.port);
  impl.acceptor.open(endpoint.protocol(), ec);
  if (!ec) impl.acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) impl.acceptor.bind(endpoint, ec);
  if (!ec) impl.acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error("cannot listen on " + where + ": " + ec.message());
  impl.port = impl.acceptor.local_endpoint().port();
  if (!options.tls_cert_file.empty() || !options.tls_key_file.empty()) {
    if (options.tls_cert_file.empty() || options.tls_key_file.empty())
      throw std::runtime_error("TLS needs both --tls-cert and --tls-key");
    impl.tls = make_tls_context(options);
  }
  impl.started = true;
  impl.accept();
  const int count = options.threads > 0 ? options.threads : 1;
  for (int i = 0; i < count; ++i) impl.threads.emplace_back([&impl] { impl.io_context.run(); });
}

uint16_t HttpServer::port() const { return impl_->port; }

std::string HttpServer::url() const {
  const std::string& address = impl_->core.options.address;
  const bool v6 = address.find(':') != std::string::npos;
  return std::string(impl_->tls ? "https://" : "http://") + (v6 ? "[" + address + "]" : address) +
         ":" + std::to_string(impl_->port);
}

void HttpServer::stop() {
  auto& impl = *impl_;
  std::lock_guard<std::mutex> stop_lock(impl.stop_mutex);
  if (!impl.started || impl.stopped) return;
  impl.stopped = true;
  impl.core.stopping = true;
  net::post(impl.acceptor.get_executor(), [&impl] {
    error_code ignored;
    impl.acceptor.close(ignored);
    impl.accept_retry.cancel();
  });
  {
    std::lock_guard<std::mutex> lock(impl.core.sessions_mutex);
    impl.core.resume_accept = nullptr;
  }
  std::vector<std::shared_ptr<SessionBase>> live;
  {
    std::lock_guard<std::mutex> lock(impl.core.sessions_mutex);
    for (auto& [raw, weak] : impl.core.sessions)
      if (auto session = weak.lock()) live.push_back(std::move(session));
  }
  // Outside the lock: dropping the last owner runs ~Session, which takes the lock.
  for (auto& session : live)
    net::post(session->executor(), [session] { session->on_server_stop(); });
  live.clear();
  {
    std::unique_lock<std::mutex> lock(impl.core.sessions_mutex);
    impl.core.sessions_done.wait_for(lock, impl.core.options.shutdown_grace,
                                     [&impl] { return impl.core.sessions.empty(); });
  }
  impl.io_context.stop();
  for (auto& thread : impl.threads) thread.join();
  impl.threads.clear();
  // The close posted above may not have run before io_context.stop(); with no thread left
  // the acceptor is ours to close, so the port refuses connections once stop() returns.
  error_code ignored;
  impl.acceptor.close(ignored);
}

}  // namespace keel::server
