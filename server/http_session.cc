#include "server/http_session.h"

#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <boost/asio/bind_executor.hpp>
#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>

#include <array>
#include <atomic>
#include <cerrno>
#include <functional>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "server/api_response.h"
#include "server/file_region_body.h"

namespace keel::server {

namespace beast = boost::beast;
namespace http = boost::beast::http;

namespace {

constexpr uint64_t kUnlimitedUntilHeader = ~uint64_t{0};

using TlsStream = beast::ssl_stream<beast::tcp_stream>;

template <class Stream>
constexpr bool kIsTls = std::is_same_v<Stream, TlsStream>;

}  // namespace
// TCP layer (deadlines, the socket) is beast::get_lowest_layer(stream_) for both.
template <class Stream>
class Session : public SessionBase, public std::enable_shared_from_this<Session<Stream>> {
 public:
  template <class... StreamArgs>
  Session(ServerCore& core, StreamArgs&&... args)
      : stream_(std::forward<StreamArgs>(args)...), core_(core) {}

  ~Session() override {
    std::function<void()> resume;
    {
      std::lock_guard<std::mutex> lock(core_.sessions_mutex);
      core_.sessions.erase(this);
      if (core_.sessions.empty()) core_.sessions_done.notify_all();
      resume.swap(core_.resume_accept);
    }
    if (resume) resume();
  }

  void start() {
    // Beast sizes each socket read by the buffer's spare capacity (at most 64 KiB): without
    // this an upload body arrives ~1 KiB per read() and uploads crawl.
    buffer_.reserve(64 * 1024);
    {
      std::lock_guard<std::mutex> lock(core_.sessions_mutex);
      core_.sessions[this] = this->weak_from_this();
    }
    net::dispatch(stream_.get_executor(), [self = this->shared_from_this()] { self->handshake(); });
  }

  // Called on the session's strand when the server stops: an idle connection (waiting for
  // a request) closes now; a request in flight finishes and then closes; a long poll
  // answers now and an event stream ends.
  void on_server_stop() override {
    if (idle_) tcp().cancel();
    if (pending_) on_pending_wake(true);
    if (event_stream_) {
      stream_final_ = true;
      pump_stream();
    }
  }

  net::any_io_executor executor() override { return stream_.get_executor(); }

 private:
  beast::tcp_stream& tcp() { return beast::get_lowest_layer(stream_); }

  // TLS: the handshake first, under the read deadline (a client that connects and says
  // nothing is dropped like an idle one). Plain TCP: straight to the first request.
  void handshake() {
    if constexpr (kIsTls<Stream>) {
      idle_ = true;
      tcp().expires_after(core_.options.read_timeout);
      stream_.async_handshake(net::ssl::stream_base::server,
                              [self = this->shared_from_this()](error_code ec) {
                                self->idle_ = false;
                                if (ec) return self->close();
                                self->read_header();
                              });
    } else {
      read_header();
    }
  }

  // --- reading ---
  void read_header() {
    if (core_.stopping) return close();
    parser_.emplace();
    parser_->header_limit(core_.options.header_limit_bytes);
    parser_->body_limit(kUnlimitedUntilHeader);
    idle_ = true;
    tcp().expires_after(core_.options.read_timeout);
    http::async_read_header(
        stream_, buffer_, *parser_,
        [self = this->shared_from_this()](error_code ec, size_t) { self->on_header(ec); });
  }

  void on_header(error_code ec) {
    idle_ = false;
    if (ec == http::error::header_limit)
      return send_error(
          431, "too_large",
          "request header over " + std::to_string(core_.options.header_limit_bytes) + " bytes");
    if (ec == http::error::end_of_stream || ec == net::error::eof || ec == beast::error::timeout ||
        ec == net::error::operation_aborted || ec == net::error::connection_reset)
      return close();
    if (ec && ec.category() == http::make_error_code(http::error::end_of_stream).category())
      return send_error(400, "bad_request", "malformed HTTP request: " + ec.message());
    if (ec) return close();

    const auto& header = parser_->get();
    const uint64_t limit =
        core_.handler.body_limit(std::string(header.method_string()), std::string(header.target()));
    if (auto length = parser_->content_length(); length && *length > limit)
      return send_error(413, "too_large",
                        "body of " + std::to_string(*length) +
                            " bytes is over this route's limit of " + std::to_string(limit));
    parser_->body_limit(limit);
    if (parser_->is_done()) return handle_request();
    if (beast::iequals(header[http::field::expect], "100-continue")) return send_continue();
    read_body();
  }

  void send_continue() {
    auto reply = std::make_shared<http::response<http::empty_body>>(http::status::continue_, 11);
    tcp().expires_after(core_.options.write_timeout);
    http::async_write(stream_, *reply,
                      [self = this->shared_from_this(), reply](error_code ec, size_t) {
                        if (ec) return self->close();
                        self->read_body();
                      });
  }

  // The body is read piece by piece with a fresh deadline each time: a slow uplink that keeps
  // sending survives, a stalled one is dropped. A cut connection never reaches the handler,
  // so a partial chunk commits nothing.
  void read_body() {
    tcp().expires_after(core_.options.read_timeout);
    http::async_read_some(
        stream_, buffer_, *parser_,
        [self = this->shared_from_this()](error_code ec, size_t) { self->on_body(ec); });
  }

  void on_body(error_code ec) {
    if (ec == http::error::body_limit)
      return send_error(413, "too_large", "body is over this route's limit");
    if (ec) return close();
    if (!parser_->is_done()) return read_body();
    handle_request();
  }

  // --- answering ---
  void handle_request() {
    http::request<http::string_body> message = parser_->release();
    Request request;
    request.method = std::string(message.method_string());
    request.target = std::string(message.target());
    for (const auto& field : message)
      request.headers.add(std::string(field.name_string()), std::string(field.value()));
    request.body = std::move(message.body());
    const bool keep_alive = message.keep_alive();
    const unsigned version = message.version();
    const bool head = message.method() == http::verb::head;

    Response response = core_.handler.handle(request);
    if (response.pending)
      return begin_pending(std::move(response.pending), version, keep_alive, head);
    if (response.stream) return begin_stream(std::move(response), version);
    write_response(std::move(response), version, keep_alive && !core_.stopping, head);
  }

  // --- long polls (PendingResponse) ---
  // Nothing is read or written while waiting; the answer is written like any other.
  std::function<void()> waker(void (Session::*method)()) {
    std::weak_ptr<Session> weak = this->weak_from_this();
    return [weak, method] {
      if (auto self = weak.lock())
        net::post(self->executor(), [self, method] { ((*self).*method)(); });
    };
  }

  void begin_pending(std::shared_ptr<PendingResponse> pending, unsigned version, bool keep_alive,
                     bool head) {
    pending_ = std::move(pending);
    pending_version_ = version;
    pending_keep_alive_ = keep_alive;
    pending_head_ = head;
    timer_.emplace(stream_.get_executor());
    pending_->start(waker(&Session::on_pending_notified));
    arm_pending_timer();
  }

  void on_pending_notified() { on_pending_wake(false); }

  void arm_pending_timer() {
    const auto now = std::chrono::steady_clock::now();
    timer_->expires_at(std::min(pending_->deadline(), now + pending_->tick()));
    timer_->async_wait([self = this->shared_from_this()](error_code ec) {
      if (ec == net::error::operation_aborted || !self->pending_) return;
      self->on_pending_wake(std::chrono::steady_clock::now() >= self->pending_->deadline());
    });
  }

  // True when the client closed its side (or the socket failed): peeking never consumes
  // a byte, so a pipelined next request stays for the parser.
  bool peer_gone() {
    char byte;
    const ssize_t n = ::recv(tcp().socket().native_handle(), &byte, 1, MSG_PEEK | MSG_DONTWAIT);
    return n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR);
  }

  void on_pending_wake(bool final) {
    if (!pending_) return;
    // A worker that hung up must not be handed a lease it will never run.
    if (peer_gone()) {
      pending_.reset();
      timer_->cancel();
      return close();
    }
    std::optional<Response> answer = pending_->poll(final || core_.stopping);
    if (!answer) return arm_pending_timer();
    pending_.reset();
    timer_->cancel();
    core_.handler.count_response(answer->status);
    write_response(std::move(*answer), pending_version_, pending_keep_alive_ && !core_.stopping,
                   pending_head_);
  }

  // --- event streams (EventStream, server-sent events) ---
  void begin_stream(Response response, unsigned version) {
    event_stream_ = std::move(response.stream);
    auto header = std::make_shared<http::response<http::empty_body>>();
    header->version(version);
    set_common(*header, response, false);
    header->chunked(true);
    auto serializer = std::make_shared<http::response_serializer<http::empty_body>>(*header);
    tcp().expires_after(core_.options.write_timeout);
    http::async_write_header(
        stream_, *serializer,
        [self = this->shared_from_this(), header, serializer](error_code ec, size_t) {
          if (ec) return self->end_stream(false);
          self->timer_.emplace(self->stream_.get_executor());
          self->event_stream_->start(self->waker(&Session::pump_stream));
          self->pump_stream();
        });
  }

  void pump_stream() {
    if (!event_stream_ || !timer_) return;
    if (stream_writing_) {
      stream_dirty_ = true;
      return;
    }
    bool ended = false;
    std::string data = event_stream_->take(stream_final_ || core_.stopping, ended);
    if (data.empty() && !ended) {
      if (peer_gone()) return end_stream(false);
      timer_->expires_after(event_stream_->tick());
      timer_->async_wait([self = this->shared_from_this()](error_code ec) {
        if (ec == net::error::operation_aborted) return;
        self->pump_stream();
      });
      return;
    }
    stream_writing_ = true;
    stream_dirty_ = false;
    auto bytes = std::make_shared<std::string>(std::move(data));
    auto after = [self = this->shared_from_this(), bytes, ended](error_code ec, size_t) {
      self->stream_writing_ = false;
      if (ec) return self->end_stream(false);
      if (ended) return self->end_stream(true);
      self->pump_stream();
    };
    tcp().expires_after(core_.options.write_timeout);
    if (bytes->empty())
      after(error_code(), 0);
    else
      net::async_write(stream_, http::make_chunk(net::buffer(*bytes)), std::move(after));
  }

  // Ends the event stream: with `clean`, the last chunk tells the client it is complete.
  void end_stream(bool clean) {
    if (timer_) timer_->cancel();
    event_stream_.reset();
    if (!clean) return close();
    tcp().expires_after(core_.options.write_timeout);
    net::async_write(stream_, http::make_chunk_last(),
                     [self = this->shared_from_this()](error_code, size_t) { self->close(); });
  }

  void send_error(int status, const std::string& code, const std::string& message) {
    core_.handler.count_response(status);
    const unsigned version = parser_ ? parser_->get().version() : 11;
    drain_after_write_ = true;
    write_response(error_response(status, code, message), version == 10 ? 10 : 11, false, false);
  }

  template <class Body>
  void set_common(http::response<Body>& message, const Response& response, bool keep_alive) {
    message.result(static_cast<unsigned>(response.status));
    for (const auto& [name, value] : response.headers.fields()) message.set(name, value);
    message.set(http::field::server, "keel-server");
    message.keep_alive(keep_alive);
  }

  void write_response(Response response, unsigned version, bool keep_alive, bool head) {
    if (response.file) {
      FileRegionBody::value_type body;
      error_code ec;
      body.open(response.file->path, response.file->offset, response.file->length, ec);
      if (!ec) {
        http::response<FileRegionBody> message;
        message.version(version);
        set_common(message, response, keep_alive);
        message.body() = std::move(body);
        message.prepare_payload();
        return write_message(std::move(message), !keep_alive, head);
      }
      spdlog::error("cannot open {} for an answer: {}", response.file->path.string(), ec.message());
      response = error_response(500, "internal", "stored file cannot be read");
      core_.handler.count_response(500);
    }
    http::response<http::string_body> message;
    message.version(version);
    set_common(message, response, keep_alive);
    message.body() = std::move(response.body);
    const int status = response.status;
    if (status < 200 || status == 204 || status == 304)
      message.erase(http::field::content_length);  // these carry no body (RFC 9110 8.6)
    else
      message.prepare_payload();
    write_message(std::move(message), !keep_alive, head);
  }

  // Writes piece by piece with a fresh deadline for each, so a large download to a slow but
  // live reader is not cut while a reader that stops reading is.
  template <class Body>
  void write_message(http::response<Body>&& message, bool close_after, bool head) {
    auto held = std::make_shared<http::response<Body>>(std::move(message));
    auto serializer = std::make_shared<http::response_serializer<Body>>(*held);
    if (head) serializer->split(true);
    write_some(held, serializer, close_after, head);
  }

  template <class Body>
  void write_some(std::shared_ptr<http::response<Body>> held,
                  std::shared_ptr<http::response_serializer<Body>> serializer, bool close_after,
                  bool head) {
    tcp().expires_after(core_.options.write_timeout);
    auto next = [self = this->shared_from_this(), held, serializer, close_after, head](
                    error_code ec, size_t) {
      if (ec) return self->close();
      const bool done = head ? serializer->is_header_done() : serializer->is_done();
      if (!done) return self->write_some(held, serializer, close_after, head);
      if (close_after) return self->drain_after_write_ ? self->drain_and_close() : self->close();
      self->read_header();
    };
    if (head)
      http::async_write_header(stream_, *serializer, std::move(next));
    else
      http::async_write_some(stream_, *serializer, std::move(next));
  }

  // After an early error answer the client may still be sending a body; closing with unread
  // bytes would reset the connection and the client could lose the answer. So: stop sending,
  // read and drop what still comes (bounded in time and bytes), then close.
  void drain_and_close() {
    error_code ignored;
    tcp().socket().shutdown(tcp::socket::shutdown_send, ignored);
    drain_deadline_ = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    drain_some();
  }

  void drain_some() {
    constexpr size_t kMaxDrainBytes = 256ull << 20;
    if (drained_ > kMaxDrainBytes || std::chrono::steady_clock::now() >= drain_deadline_)
      return close();
    tcp().expires_at(drain_deadline_);
    stream_.async_read_some(net::buffer(drain_buffer_),
                            [self = this->shared_from_this()](error_code ec, size_t n) {
                              if (ec) return self->close();
                              self->drained_ += n;
                              self->drain_some();
                            });
  }

  // TLS connections are closed without waiting for the client's close_notify: every answer
  // is framed (Content-Length or chunked), so a client cannot take a cut for the end.
  void close() {
    error_code ignored;
    tcp().socket().shutdown(tcp::socket::shutdown_send, ignored);
    tcp().close();
  }

  Stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  ServerCore& core_;
  bool idle_ = false;
  bool drain_after_write_ = false;
  std::chrono::steady_clock::time_point drain_deadline_;
  size_t drained_ = 0;
  std::array<char, 16 * 1024> drain_buffer_;
  std::optional<net::steady_timer> timer_;  // long-poll deadline / event-stream tick
  std::shared_ptr<PendingResponse> pending_;
  unsigned pending_version_ = 11;
  bool pending_keep_alive_ = true;
  bool pending_head_ = false;
  std::shared_ptr<EventStream> event_stream_;
  bool stream_writing_ = false;
  bool stream_dirty_ = false;
  bool stream_final_ = false;
};

void start_session(ServerCore& core, tcp::socket socket, net::ssl::context* tls) {
  if (tls)
    std::make_shared<Session<TlsStream>>(core, std::move(socket), *tls)->start();
  else
    std::make_shared<Session<beast::tcp_stream>>(core, std::move(socket))->start();
}

}  // namespace keel::server
