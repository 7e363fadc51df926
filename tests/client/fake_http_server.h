// A scripted HTTP/1.1 server on 127.0.0.1 for client tests: each request goes to a handler
// that returns the raw bytes to answer and whether to close the connection afterwards, so
// tests can cut links mid-body, close idle connections or never answer.
#pragma once

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include <atomic>
#include <functional>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace keel::client::testing {

struct FakeReply {
  std::string raw;           // status line, headers and (part of) the body
  bool close_after = false;  // close the connection after writing `raw`
  bool no_answer = false;    // read the request but never answer (until the client leaves)
};

using FakeRequest = boost::beast::http::request<boost::beast::http::string_body>;

// "HTTP/1.1 <status> X\r\nContent-Length: n\r\n<extra>\r\n<body>"
inline std::string http_reply(int status, const std::string& body,
                              const std::string& extra_headers = "") {
  return "HTTP/1.1 " + std::to_string(status) +
         " X\r\nContent-Length: " + std::to_string(body.size()) + "\r\n" + extra_headers + "\r\n" +
         body;
}

class FakeHttpServer {
 public:
  using Handler = std::function<FakeReply(const FakeRequest&)>;

  explicit FakeHttpServer(Handler handler)
      : handler_(std::move(handler)),
        acceptor_(ioc_, {boost::asio::ip::make_address("127.0.0.1"), 0}) {
    thread_ = std::thread([this] { serve(); });
  }
  ~FakeHttpServer() {
    stop_ = true;
    boost::system::error_code ignored;
    // Wakes the blocking accept with a throw-away connection.
    boost::asio::io_context ioc;
    boost::asio::ip::tcp::socket poke(ioc);
    poke.connect(acceptor_.local_endpoint(), ignored);
    thread_.join();
  }

  std::string url() const {
    return "http://127.0.0.1:" + std::to_string(acceptor_.local_endpoint().port());
  }

  std::vector<FakeRequest> requests() {
    std::lock_guard<std::mutex> lock(mutex_);
    return requests_;
  }
  int connections() const { return connections_; }

 private:
  void serve() {
    while (!stop_) {
      boost::asio::ip::tcp::socket socket(ioc_);
      boost::system::error_code ec;
      acceptor_.accept(socket, ec);
      if (ec || stop_) return;
      ++connections_;
      serve_connection(socket);
    }
  }

  void serve_connection(boost::asio::ip::tcp::socket& socket) {
    namespace http = boost::beast::http;
    boost::beast::flat_buffer buffer;
    while (!stop_) {
      http::request_parser<http::string_body> parser;
      parser.body_limit(std::numeric_limits<std::uint64_t>::max());
      boost::system::error_code ec;
      http::read(socket, buffer, parser, ec);
      if (ec) return;
      FakeRequest request = parser.release();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        requests_.push_back(request);
      }
      const FakeReply reply = handler_(request);
      if (reply.no_answer) {
        char byte;
        socket.read_some(boost::asio::buffer(&byte, 1), ec);  // until the client gives up
        return;
      }
      boost::asio::write(socket, boost::asio::buffer(reply.raw), ec);
      if (ec || reply.close_after) return;
    }
  }

  Handler handler_;
  boost::asio::io_context ioc_;
  boost::asio::ip::tcp::acceptor acceptor_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> connections_{0};
  std::mutex mutex_;
  std::vector<FakeRequest> requests_;
};

}  // namespace keel::client::testing
