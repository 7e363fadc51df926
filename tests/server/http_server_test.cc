// The socket side on an ephemeral loopback port, driven by a raw client that can cut
// connections, stall and send oversized headers or bodies.
#include "server/http_server.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>

#include "core/sha256.h"
#include "tests/server/handler_fixture.h"
#include "tests/server/raw_http_client.h"

namespace keel::server::testing {
namespace {

using namespace std::chrono_literals;

class HttpServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    store_ = storage::open_sqlite_store(dir_.path());
    store_->add_token(token_, storage::admin_token("tests"));
    HandlerOptions handler_options;
    handler_options.max_chunk_bytes = 1 << 20;
    handler_ = std::make_unique<HttpHandler>(*store_, handler_options);
  }
  void TearDown() override {
    if (server_) server_->stop();
  }

  void start(std::chrono::milliseconds read_timeout = 5000ms, int max_connections = 4096) {
    ServerOptions options;
    options.port = 0;
    options.max_connections = max_connections;
    options.threads = 2;
    options.read_timeout = read_timeout;
    options.shutdown_grace = 2000ms;
    server_ = std::make_unique<HttpServer>(*handler_, options);
    server_->start();
    ASSERT_NE(server_->port(), 0);
  }

  std::unique_ptr<RawClient> client() { return std::make_unique<RawClient>(server_->port()); }

  std::string request(const std::string& method, const std::string& target,
                      const std::string& body = "",
                      const std::map<std::string, std::string>& headers = {}) {
    return http_request(method, target, token_, body, headers);
  }

  HttpReply must(std::optional<HttpReply> reply) {
    if (!reply) {
      ADD_FAILURE() << "no reply";
      return {};
    }
    return *reply;
  }

  std::string new_upload(RawClient& c, size_t size) {
    HttpReply reply = must(c.exchange(request(
        "POST", "/v1/uploads", nlohmann::json{{"name", "big.bin"}, {"size", size}}.dump())));
    EXPECT_EQ(reply.status, 201) << reply.body;
    return nlohmann::json::parse(reply.body)["id"];
  }

  std::string chunk_header(const std::string& id, size_t first, size_t length, size_t total) {
    return "PUT /v1/uploads/" + id + " HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " + token_ +
           "\r\nContent-Range: bytes " + std::to_string(first) + "-" +
           std::to_string(first + length - 1) + "/" + std::to_string(total) +
           "\r\nContent-Length: " + std::to_string(length) + "\r\n\r\n";
  }

  int64_t committed(RawClient& c, const std::string& id) {
    HttpReply reply = must(c.exchange(request("HEAD", "/v1/uploads/" + id), /*head=*/true));
    EXPECT_EQ(reply.status, 200);
    return std::stoll(reply.header("upload-offset"));
  }

  TempDir dir_;
  std::string token_ = "socket-test-token";
  std::unique_ptr<storage::Store> store_;
  std::unique_ptr<HttpHandler> handler_;
  std::unique_ptr<HttpServer> server_;
};

TEST_F(HttpServerTest, KeepAliveServesSeveralRequestsOnOneConnection) {
  start();
  auto c = client();
  for (int i = 0; i < 3; ++i) {
    HttpReply health = must(c->exchange(request("GET", "/healthz")));
    EXPECT_EQ(health.status, 200);
    EXPECT_EQ(nlohmann::json::parse(health.body)["status"], "ok");
  }
  HttpReply denied = must(c->exchange(http_request("GET", "/v1/jobs", "")));
  EXPECT_EQ(denied.status, 401);
  HttpReply jobs = must(c->exchange(request("GET", "/v1/jobs")));
  EXPECT_EQ(jobs.status, 200);
  EXPECT_EQ(jobs.body, "{\"jobs\":[]}");
  EXPECT_EQ(server_->url(), "http://127.0.0.1:" + std::to_string(server_->port()));
}

TEST_F(HttpServerTest, CutConnectionMidChunkCommitsNothingAndResumeCompletes) {
  start();
  const size_t chunk = 1 << 20, total = 2 * chunk;
  const std::string bytes = random_bytes(total, 11);
  auto control = client();
  const std::string id = new_upload(*control, total);

  {  // half of the first chunk, then the link drops
    auto cut = client();
    ASSERT_TRUE(cut->send(chunk_header(id, 0, chunk, total) + bytes.substr(0, 600'000)));
    std::this_thread::sleep_for(100ms);
  }
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(committed(*control, id), 0);

  HttpReply first =
      must(control->exchange(chunk_header(id, 0, chunk, total) + bytes.substr(0, chunk)));
  ASSERT_EQ(first.status, 200) << first.body;
  {  // the second chunk is cut too
    auto cut = client();
    ASSERT_TRUE(cut->send(chunk_header(id, chunk, chunk, total) + bytes.substr(chunk, chunk - 1)));
  }
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(committed(*control, id), static_cast<int64_t>(chunk));

  HttpReply second =
      must(control->exchange(chunk_header(id, chunk, chunk, total) + bytes.substr(chunk)));
  ASSERT_EQ(second.status, 200) << second.body;
  const std::string sha = keel::sha256_bytes(bytes);
  HttpReply done = must(control->exchange(
      request("POST", "/v1/uploads/" + id + "/complete", nlohmann::json{{"sha256", sha}}.dump())));
  ASSERT_EQ(done.status, 200) << done.body;
  EXPECT_EQ(nlohmann::json::parse(done.body)["blob"], sha);

  HttpReply blob = must(control->exchange(request("GET", "/v1/blobs/" + sha)));
  ASSERT_EQ(blob.status, 200);
  EXPECT_EQ(keel::sha256_bytes(blob.body), sha);
}

TEST_F(HttpServerTest, HeaderOverTheLimitGives431AndTheServerStaysUp) {
  start();
  {
    auto c = client();
    HttpReply reply =
        must(c->exchange(request("GET", "/healthz", "", {{"X-Fill", std::string(20'000, 'a')}})));
    EXPECT_EQ(reply.status, 431);
    EXPECT_EQ(nlohmann::json::parse(reply.body)["error"]["code"], "too_large");
    EXPECT_TRUE(c->wait_closed());
  }
  auto c = client();
  EXPECT_EQ(must(c->exchange(request("GET", "/healthz"))).status, 200);
}

TEST_F(HttpServerTest, BodyOverTheRouteLimitGives413) {
  start();
  auto control = client();
  const std::string id = new_upload(*control, 4 << 20);
  {  // announced too large: answered from the header alone, even while the body streams in
    auto c = client();
    const std::string body(2 << 20, 'x');
    ASSERT_TRUE(c->send(chunk_header(id, 0, body.size(), 4 << 20) + body));
    HttpReply reply = must(c->read_reply());
    EXPECT_EQ(reply.status, 413);
    EXPECT_EQ(nlohmann::json::parse(reply.body)["error"]["code"], "too_large");
  }
  {  // JSON routes allow 1 MiB
    auto c = client();
    HttpReply reply =
        must(c->exchange(request("POST", "/v1/jobs", std::string((1 << 20) + 1, ' '))));
    EXPECT_EQ(reply.status, 413);
  }
  {  // a chunked body has no length up front: it is cut when it passes the limit
    auto c = client();
    std::string chunked = "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nAuthorization: Bearer " + token_ +
                          "\r\nTransfer-Encoding: chunked\r\n\r\n";
    const std::string piece(256 * 1024, ' ');
    for (int i = 0; i < 5; ++i) chunked += "40000\r\n" + piece + "\r\n";
    chunked += "0\r\n\r\n";
    c->send(chunked);
    HttpReply reply = must(c->read_reply());
    EXPECT_EQ(reply.status, 413);
  }
  EXPECT_EQ(committed(*control, id), 0);
  EXPECT_EQ(handler_->counters().by_class(4), 3);
}

TEST_F(HttpServerTest, IdleAndStalledConnectionsAreDroppedAfterTheDeadline) {
  start(300ms);
  auto control = std::make_unique<RawClient>(server_->port());
  const std::string id = new_upload(*control, 100);
  control.reset();

  auto idle = client();
  EXPECT_TRUE(idle->wait_closed());
  auto partial_header = client();
  ASSERT_TRUE(partial_header->send("GET /healthz HTTP/1.1\r\nHost: x\r\n"));
  EXPECT_TRUE(partial_header->wait_closed());
  auto stalled_body = client();
  ASSERT_TRUE(stalled_body->send(chunk_header(id, 0, 100, 100) + std::string(10, 'y')));
  EXPECT_TRUE(stalled_body->wait_closed());

  auto c = client();
  EXPECT_EQ(committed(*c, id), 0);
}

TEST_F(HttpServerTest, LargeFilesStreamWithRanges) {
  start();
  const std::string bytes = random_bytes(8 << 20, 12);
  const std::string sha = store_->put_blob(bytes);
  auto c = client();
  HttpReply part = must(
      c->exchange(request("GET", "/v1/blobs/" + sha, "", {{"Range", "bytes=1000000-5999999"}})));
  ASSERT_EQ(part.status, 206);
  EXPECT_EQ(part.header("content-range"), "bytes 1000000-5999999/8388608");
  EXPECT_EQ(part.body, bytes.substr(1'000'000, 5'000'000));
  HttpReply full = must(c->exchange(request("GET", "/v1/blobs/" + sha)));
  ASSERT_EQ(full.status, 200);
  EXPECT_EQ(full.body.size(), bytes.size());
  EXPECT_EQ(keel::sha256_bytes(full.body), sha);
  HttpReply not_modified = must(
      c->exchange(request("GET", "/v1/blobs/" + sha, "", {{"If-None-Match", "\"" + sha + "\""}})));
  EXPECT_EQ(not_modified.status, 304);
  EXPECT_EQ(not_modified.header("content-length"), "");
  HttpReply bad =
      must(c->exchange(request("GET", "/v1/blobs/" + sha, "", {{"Range", "bytes=9000000-"}})));
  EXPECT_EQ(bad.status, 416);
  EXPECT_EQ(bad.header("content-range"), "bytes */8388608");
  EXPECT_EQ(must(c->exchange(request("GET", "/healthz"))).status, 200);  // framing intact
}

TEST_F(HttpServerTest, ExpectContinueAndHead) {
  start();
  auto c = client();
  const std::string id = new_upload(*c, 5);
  std::string header = chunk_header(id, 0, 5, 5);
  header.insert(header.size() - 2, "Expect: 100-continue\r\n");
  ASSERT_TRUE(c->send(header));
  HttpReply interim = must(c->read_reply());
  EXPECT_EQ(interim.status, 100);
  ASSERT_TRUE(c->send("hello"));
  HttpReply reply = must(c->read_reply());
  EXPECT_EQ(reply.status, 200) << reply.body;
  HttpReply head = must(c->exchange(request("HEAD", "/v1/uploads/" + id), true));
  EXPECT_EQ(head.header("upload-offset"), "5");
  EXPECT_EQ(head.header("upload-length"), "5");
  EXPECT_EQ(must(c->exchange(request("GET", "/v1/uploads/" + id))).status, 200);
}

TEST_F(HttpServerTest, MalformedRequestGets400) {
  start();
  auto c = client();
  HttpReply reply = must(c->exchange("GET /healthz HTTP/1.1\r\nBad Header Line\r\n\r\n"));
  EXPECT_EQ(reply.status, 400);
  EXPECT_EQ(nlohmann::json::parse(reply.body)["error"]["code"], "bad_request");
}

TEST_F(HttpServerTest, StopClosesIdleConnectionsAndRefusesNewOnes) {
  start(30'000ms);
  auto idle = client();
  EXPECT_EQ(must(idle->exchange(request("GET", "/healthz"))).status, 200);
  const uint16_t port = server_->port();
  server_->stop();
  EXPECT_TRUE(idle->wait_closed());
  EXPECT_THROW(RawClient{port}, std::runtime_error);
}

TEST_F(HttpServerTest, AtMaxConnectionsANewOneWaitsUntilOneEnds) {
  start(5000ms, /*max_connections=*/2);
  auto a = client();
  auto b = client();
  EXPECT_EQ(must(a->exchange(request("GET", "/healthz"))).status, 200);
  EXPECT_EQ(must(b->exchange(request("GET", "/healthz"))).status, 200);
  RawClient c(server_->port(), /*timeout_ms=*/1000);  // connected by the kernel's queue
  ASSERT_TRUE(c.send(request("GET", "/healthz")));
  EXPECT_FALSE(c.read_reply()) << "a third connection was served with max_connections 2";
  a.reset();
  const std::optional<HttpReply> late = c.read_reply();
  ASSERT_TRUE(late) << "the waiting connection was not served once one ended";
  EXPECT_EQ(late->status, 200);
}

// A slowloris: 500 connections each sending one header byte per second. Other clients are
// served all along, and every slow connection is dropped at the header deadline.
TEST_F(HttpServerTest, SlowHeaderClientsDoNotStopOthersAndAreDroppedAtTheDeadline) {
  struct rlimit files {};
  getrlimit(RLIMIT_NOFILE, &files);
  if (files.rlim_cur < 2048 && files.rlim_max >= 2048) {
    files.rlim_cur = 2048;
    setrlimit(RLIMIT_NOFILE, &files);
  }
  start(3000ms);
  constexpr int kSlow = 500;
  std::vector<std::unique_ptr<RawClient>> slow;
  for (int i = 0; i < kSlow; ++i)
    slow.push_back(std::make_unique<RawClient>(server_->port(), /*timeout_ms=*/10000));
  const std::string header =
      "GET /healthz HTTP/1.1\r\nHost: slow\r\nX-Pad: " + std::string(64, 'a');
  std::atomic<bool> stop{false};
  std::thread sender([&] {
    for (size_t byte = 0; byte < header.size() && !stop; ++byte) {
      for (auto& c : slow) c->send(header.substr(byte, 1));
      for (int i = 0; i < 10 && !stop; ++i) std::this_thread::sleep_for(100ms);
    }
  });
  int served = 0, failed = 0;
  double slowest_ms = 0;
  const auto until = std::chrono::steady_clock::now() + 5s;
  while (std::chrono::steady_clock::now() < until) {
    const auto start_time = std::chrono::steady_clock::now();
    RawClient c(server_->port(), 5000);
    const std::optional<HttpReply> reply = c.exchange(request("GET", "/v1/jobs"));
    (reply && reply->status == 200 ? served : failed)++;
    slowest_ms = std::max(slowest_ms, std::chrono::duration<double, std::milli>(
                                          std::chrono::steady_clock::now() - start_time)
                                          .count());
    std::this_thread::sleep_for(20ms);
  }
  stop = true;
  sender.join();
  EXPECT_EQ(failed, 0);
  EXPECT_GT(served, 20);
  int closed = 0;
  for (auto& c : slow) closed += c->wait_closed() ? 1 : 0;
  EXPECT_EQ(closed, kSlow) << "slow connections still open after the 3 s header deadline";
  std::cout << "served " << served << " requests beside " << kSlow << " slow clients; slowest "
            << slowest_ms << " ms\n";
}

}  // namespace
}  // namespace keel::server::testing
