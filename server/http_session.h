// Internal to keel-server's socket side (http_server.cc, http_session.cc): the state the
// acceptor shares with its sessions, and a session: one keep-alive HTTP/1.1 connection, plain
// or TLS, that reads each request header first, applies the route's body limit, and answers
// (streamed files, long polls, event streams) under per-read and per-write deadlines.
#pragma once

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl/context.hpp>

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>

#include "server/http_server.h"

namespace keel::server {

namespace net = boost::asio;
using tcp = net::ip::tcp;
using error_code = boost::system::error_code;

// What the server keeps of a session, whatever its stream (plain TCP or TLS).
class SessionBase {
 public:
  virtual ~SessionBase() = default;
  // Called on the session's strand when the server stops.
  virtual void on_server_stop() = 0;
  virtual net::any_io_executor executor() = 0;
};

// State shared by the acceptor and every session.
struct ServerCore {
  HttpHandler& handler;
  ServerOptions options;
  std::atomic<bool> stopping{false};

  std::mutex sessions_mutex;
  std::condition_variable sessions_done;
  std::map<const SessionBase*, std::weak_ptr<SessionBase>> sessions;
  // Set when the acceptor stopped at max_connections; the session that ends first resumes it.
  std::function<void()> resume_accept;

  ServerCore(HttpHandler& h, ServerOptions o) : handler(h), options(std::move(o)) {}
};

// Starts serving `socket` (on its strand) over TLS when `tls` is set, plain HTTP otherwise. The
// session registers itself in core.sessions and lives as long as the connection.
void start_session(ServerCore& core, tcp::socket socket, net::ssl::context* tls);

}  // namespace keel::server
