// ApiClient against a scripted loopback server: headers, keep-alive and reconnect, error
// mapping, deadlines, chunked resumable upload and Range download resume.
#include "client/api_client.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <thread>

#include "fake_http_server.h"
#include "core/sha256.h"
#include "tests/temp_dir.h"

namespace keel::client {
namespace {

namespace fs = std::filesystem;
using testing::FakeHttpServer;
using testing::FakeReply;
using testing::FakeRequest;
using testing::http_reply;
using keel::testing::read_file;
using keel::testing::TempDir;
using keel::testing::write_file;

std::string random_bytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::string out(n, '\0');
  for (auto& c : out) c = static_cast<char>(rng() & 0xff);
  return out;
}

ClientConfig config_for(const FakeHttpServer& server) {
  ClientConfig config;
  config.url = server.url();
  config.token = "secret-token";
  config.timeout_s = 5.0;
  config.retry_backoff_s = 0.0;
  return config;
}

std::string header(const FakeRequest& request, const char* name) {
  return std::string(request[name]);
}

TEST(ApiClient, SendsBearerTokenAndReusesTheConnection) {
  FakeHttpServer server(
      [](const FakeRequest&) { return FakeReply{http_reply(200, R"({"jobs":[]})")}; });
  {
    ApiClient client(config_for(server));
    EXPECT_TRUE(client.list_jobs().empty());
    EXPECT_TRUE(client.list_jobs("queued").empty());
    EXPECT_EQ(client.stats().connections, 1);
  }
  const auto requests = server.requests();
  ASSERT_EQ(requests.size(), 2u);
  EXPECT_EQ(header(requests[0], "Authorization"), "Bearer secret-token");
  EXPECT_EQ(requests[0].target(), "/v1/jobs");
  EXPECT_EQ(requests[1].target(), "/v1/jobs?state=queued");
}

TEST(ApiClient, ReconnectsWhenTheServerClosedTheIdleConnection) {
  // Every answer claims keep-alive but the server closes right after it, as an idle
  // timeout would: each next request must transparently use a new connection.
  FakeHttpServer server([](const FakeRequest&) {
    return FakeReply{http_reply(200, R"({"missions":[]})"), /*close_after=*/true};
  });
  {
    ApiClient client(config_for(server));
    for (int i = 0; i < 3; ++i) EXPECT_NO_THROW(client.list_missions("usv"));
    EXPECT_EQ(client.stats().connections, 3);
  }
  EXPECT_EQ(server.requests().size(), 3u);
}

TEST(ApiClient, PostAfterAnIdleCloseUsesANewConnection) {
  FakeHttpServer server([](const FakeRequest&) {
    return FakeReply{http_reply(200, R"({"jobs":[]})"), /*close_after=*/true};
  });
  {
    ApiClient client(config_for(server));
    client.list_jobs();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the FIN arrives
    proto::ReprocessRequest request;
    request.stages = {"ingest"};
    EXPECT_TRUE(client.reprocess(request).jobs.empty());
    EXPECT_EQ(client.stats().connections, 2);
  }
  EXPECT_EQ(server.requests().size(), 2u);  // the POST was sent exactly once
}

TEST(ApiClient, NonSuccessCarriesTheServersCodeAndMessage) {
  FakeHttpServer server([](const FakeRequest&) {
    return FakeReply{
        http_reply(404, R"({"error":{"code":"not_found","message":"job j9 not found"}})")};
  });
  ApiClient client(config_for(server));
  try {
    client.get_job("j9");
    FAIL() << "expected ApiCallError";
  } catch (const ApiCallError& e) {
    EXPECT_EQ(e.status(), 404);
    EXPECT_EQ(e.code(), "not_found");
    EXPECT_STREQ(e.what(), "job j9 not found");
  }
  // A non-JSON error body still gives the status and a code derived from it.
  FakeHttpServer plain(
      [](const FakeRequest&) { return FakeReply{http_reply(502, "bad gateway")}; });
  ApiClient plain_client(config_for(plain));
  try {
    plain_client.get_json("/v1/jobs");
    FAIL() << "expected ApiCallError";
  } catch (const ApiCallError& e) {
    EXPECT_EQ(e.status(), 502);
    EXPECT_EQ(e.code(), "http_502");
  }
}

TEST(ApiClient, UnreachableServerIsATransportErrorNamingTheUrl) {
  // Bind and release a port so nothing listens on it.
  boost::asio::io_context ioc;
  boost::asio::ip::tcp::acceptor acceptor(ioc, {boost::asio::ip::make_address("127.0.0.1"), 0});
  const int port = acceptor.local_endpoint().port();
  acceptor.close();
  ClientConfig config;
  config.url = "http://127.0.0.1:" + std::to_string(port);
  ApiClient client(config);
  try {
    client.get_json("/v1/jobs");
    FAIL() << "expected ApiCallError";
  } catch (const ApiCallError& e) {
    EXPECT_EQ(e.status(), 0);
    EXPECT_EQ(e.code(), "transport");
    EXPECT_NE(std::string(e.what()).find("127.0.0.1:" + std::to_string(port) + "/v1/jobs"),
              std::string::npos)
        << e.what();
  }
}

TEST(ApiClient, DeadlineEndsARequestTheServerNeverAnswers) {
  FakeHttpServer server([](const FakeRequest&) {
    FakeReply reply;
    reply.no_answer = true;
    return reply;
  });
  ClientConfig config = config_for(server);
  config.timeout_s = 0.3;
  ApiClient client(config);
  EXPECT_THROW(
      {
        try {
          client.get_json("/v1/jobs");
        } catch (const ApiCallError& e) {
          EXPECT_EQ(e.status(), 0);
          EXPECT_NE(std::string(e.what()).find("timeout"), std::string::npos) << e.what();
          throw;
        }
      },
      ApiCallError);
}

TEST(ApiClient, LeaseReturnsNulloptOn204) {
  FakeHttpServer server(
      [](const FakeRequest&) { return FakeReply{"HTTP/1.1 204 No Content\r\n\r\n"}; });
  ApiClient client(config_for(server));
  EXPECT_FALSE(client.lease(proto::LeaseRequest{"host:1", 30}).has_value());
}

// A minimal upload endpoint: commits whole chunks at the committed offset (409 otherwise),
// and can cut the link on chosen PUTs or refuse one with offset_mismatch.
struct UploadScript {
  std::string committed;
  int64_t size = 0;
  int put_count = 0;
  std::map<int, bool> drops;  // PUT number (1-based) → commit it before cutting the link?
  int mismatch_put = -1;      // this PUT gets 409 offset_mismatch without committing

  std::string upload_json() const {
    return R"({"id":"u1","name":"f","size":)" + std::to_string(size) + R"(,"offset":)" +
           std::to_string(committed.size()) + R"(,"blob":""})";
  }
  FakeReply mismatch() const {
    return FakeReply{http_reply(409, R"({"error":{"code":"offset_mismatch","message":"resume"}})",
                                "Upload-Offset: " + std::to_string(committed.size()) + "\r\n")};
  }

  FakeReply handle(const FakeRequest& request) {
    const std::string target(request.target());
    const std::string method(request.method_string());
    if (method == "HEAD" && target == "/v1/uploads/u1")
      return FakeReply{"HTTP/1.1 200 OK\r\nUpload-Offset: " + std::to_string(committed.size()) +
                       "\r\nUpload-Length: " + std::to_string(size) +
                       "\r\nContent-Length: 0\r\n\r\n"};
    if (method == "HEAD" || method == "GET")
      return FakeReply{"HTTP/1.1 404 X\r\nContent-Length: 0\r\n\r\n"};
    if (method == "POST" && target == "/v1/uploads") {
      size = nlohmann::json::parse(request.body())["size"].get<int64_t>();
      return FakeReply{http_reply(201, upload_json())};
    }
    if (method == "PUT") {
      ++put_count;
      const std::string range(request["Content-Range"]);
      const size_t first = std::stoul(range.substr(6));
      if (put_count == mismatch_put || first != committed.size()) return mismatch();
      const auto drop = drops.find(put_count);
      if (drop == drops.end() || drop->second) committed += request.body();
      if (drop != drops.end()) return FakeReply{"", /*close_after=*/true};
      return FakeReply{http_reply(200, upload_json())};
    }
    if (method == "POST" && target == "/v1/uploads/u1/complete") {
      const std::string sha = keel::sha256_bytes(committed);
      return FakeReply{http_reply(
          200, R"({"blob":")" + sha + R"(","size":)" + std::to_string(committed.size()) + "}")};
    }
    return FakeReply{http_reply(500, "unexpected " + method + " " + target)};
  }
};

std::vector<std::string> content_ranges(const std::vector<FakeRequest>& requests) {
  std::vector<std::string> out;
  for (const auto& r : requests)
    if (r.method() == boost::beast::http::verb::put) out.push_back(header(r, "Content-Range"));
  return out;
}

TEST(ApiClientUpload, SendsChunksWithContentRangesAndCompletes) {
  TempDir dir;
  const std::string bytes = "0123456789";
  write_file(dir.path() / "f.bin", bytes);
  UploadScript script;
  FakeHttpServer server([&](const FakeRequest& r) { return script.handle(r); });
  std::vector<std::pair<int64_t, int64_t>> reports;
  {
    ClientConfig config = config_for(server);
    config.chunk_bytes = 4;
    ApiClient client(config);
    const std::string blob =
        client.upload_file(dir.path() / "f.bin", dir.path() / "state",
                           [&](int64_t d, int64_t t) { reports.emplace_back(d, t); });
    EXPECT_EQ(blob, keel::sha256_bytes(bytes));
    EXPECT_EQ(client.stats().upload_body_bytes, 10);
  }
  EXPECT_EQ(script.committed, bytes);
  // 10 bytes in 4-byte chunks: [0,3], [4,7], [8,9].
  EXPECT_EQ(content_ranges(server.requests()),
            (std::vector<std::string>{"bytes 0-3/10", "bytes 4-7/10", "bytes 8-9/10"}));
  EXPECT_EQ(reports,
            (std::vector<std::pair<int64_t, int64_t>>{{0, 10}, {4, 10}, {8, 10}, {10, 10}}));
  EXPECT_TRUE(fs::is_empty(dir.path() / "state")) << "the state file must be deleted when done";
}

TEST(ApiClientUpload, DroppedLinkAndOffsetMismatchResumeAtTheServersOffset) {
  TempDir dir;
  const std::string bytes = random_bytes(1000, 7);
  write_file(dir.path() / "f.bin", bytes);
  UploadScript script;
  // PUT 2 is lost before it commits; the connection's transparent retry (PUT 3) commits
  // but its answer is lost too, so upload_file must HEAD for the offset (512) and go on.
  // PUT 5 is refused with 409 offset_mismatch: resend from the offset the 409 names.
  script.drops = {{2, false}, {3, true}};
  script.mismatch_put = 5;
  FakeHttpServer server([&](const FakeRequest& r) { return script.handle(r); });
  {
    ClientConfig config = config_for(server);
    config.chunk_bytes = 256;
    ApiClient client(config);
    EXPECT_EQ(client.upload_file(dir.path() / "f.bin", dir.path() / "state"),
              keel::sha256_bytes(bytes));
  }
  EXPECT_EQ(script.committed, bytes);
  EXPECT_EQ(
      content_ranges(server.requests()),
      (std::vector<std::string>{"bytes 0-255/1000", "bytes 256-511/1000", "bytes 256-511/1000",
                                "bytes 512-767/1000", "bytes 768-999/1000", "bytes 768-999/1000"}));
  int offset_queries = 0;
  for (const auto& r : server.requests())
    offset_queries +=
        r.method() == boost::beast::http::verb::head && r.target() == "/v1/uploads/u1";
  EXPECT_EQ(offset_queries, 1);
}

TEST(ApiClientUpload, GivesUpAfterTheConfiguredConsecutiveFailures) {
  TempDir dir;
  write_file(dir.path() / "f.bin", "abcdef");
  int puts = 0;
  FakeHttpServer server([&](const FakeRequest& r) {
    const std::string method(r.method_string());
    if (method == "POST")
      return FakeReply{http_reply(201, R"({"id":"u1","name":"f","size":6,"offset":0,"blob":""})")};
    if (method == "HEAD" && r.target() == "/v1/uploads/u1")
      return FakeReply{"HTTP/1.1 200 OK\r\nUpload-Offset: 0\r\nContent-Length: 0\r\n\r\n"};
    if (method == "HEAD" || method == "GET")
      return FakeReply{"HTTP/1.1 404 X\r\nContent-Length: 0\r\n\r\n"};
    ++puts;
    return FakeReply{http_reply(503, R"({"error":{"code":"internal","message":"disk full"}})")};
  });
  {
    ClientConfig config = config_for(server);
    config.retries = 2;
    ApiClient client(config);
    EXPECT_THROW(client.upload_file(dir.path() / "f.bin", dir.path() / "state"), ApiCallError);
  }
  EXPECT_EQ(puts, 3);  // the first try and 2 retries
}

TEST(ApiClientDownload, CutLinkResumesWithRangeFromThePartSize) {
  TempDir dir;
  const std::string bytes = random_bytes(300000, 3);
  const size_t cut = 150000;
  FakeHttpServer server([&](const FakeRequest& r) {
    const std::string range(r["Range"]);
    if (range.empty()) {  // full answer announced, half sent, link cut
      return FakeReply{"HTTP/1.1 200 OK\r\nContent-Length: " + std::to_string(bytes.size()) +
                           "\r\n\r\n" + bytes.substr(0, cut),
                       /*close_after=*/true};
    }
    const size_t from = std::stoul(range.substr(6));
    return FakeReply{"HTTP/1.1 206 Partial Content\r\nContent-Range: bytes " +
                     std::to_string(from) + "-" + std::to_string(bytes.size() - 1) + "/" +
                     std::to_string(bytes.size()) + "\r\nContent-Length: " +
                     std::to_string(bytes.size() - from) + "\r\n\r\n" + bytes.substr(from)};
  });
  int64_t last_done = 0;
  {
    ApiClient client(config_for(server));
    client.download("/v1/blobs/x", dir.path() / "out.bin", keel::sha256_bytes(bytes),
                    [&](int64_t done, int64_t) { last_done = done; });
    EXPECT_EQ(client.stats().download_body_bytes, static_cast<int64_t>(bytes.size()));
  }
  EXPECT_EQ(read_file(dir.path() / "out.bin"), bytes);
  EXPECT_FALSE(fs::exists(dir.path() / "out.bin.part"));
  EXPECT_EQ(last_done, static_cast<int64_t>(bytes.size()));
  const auto requests = server.requests();
  ASSERT_EQ(requests.size(), 2u);
  EXPECT_EQ(header(requests[1], "Range"), "bytes=150000-");
}

TEST(ApiClientDownload, ServerIgnoringRangeRewritesThePart) {
  TempDir dir;
  const std::string bytes = "hello, world";
  write_file(dir.path() / "out.bin.part", "XXXXX");  // not a prefix of the resource
  FakeHttpServer server([&](const FakeRequest&) { return FakeReply{http_reply(200, bytes)}; });
  {
    ApiClient client(config_for(server));
    client.download("/v1/blobs/x", dir.path() / "out.bin");
  }
  EXPECT_EQ(read_file(dir.path() / "out.bin"), bytes);
}

}  // namespace
}  // namespace keel::client
