// A pure HttpHandler over a real SQLite store in a temporary folder, and helpers to call it
// the way a client would (no sockets).
#pragma once

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <string>

#include "server/http_handler.h"
#include "core/sha256.h"
#include "storage/store.h"
#include "tests/server/tar_builder.h"
#include "tests/storage/store_fixture.h"

namespace keel::server::testing {

using storage::testing::random_bytes;
using storage::testing::TempDir;

inline std::string read_region(const FileRegion& region) {
  std::ifstream in(region.path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(region.offset));
  std::string bytes(region.length, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(region.length));
  bytes.resize(static_cast<size_t>(in.gcount()));
  return bytes;
}

inline nlohmann::json json_of(const Response& response) {
  return nlohmann::json::parse(response.body);
}

inline std::string error_code_of(const Response& response) {
  auto body = nlohmann::json::parse(response.body, nullptr, false);
  if (body.is_discarded() || !body.contains("error")) return "<no error body>";
  return body["error"]["code"].get<std::string>();
}

class HandlerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    store_ = storage::open_sqlite_store(dir_.path());
    token_ = "test-token-0123456789";
    store_->add_token(token_, storage::admin_token("tests"));
    HandlerOptions options;
    options.max_chunk_bytes = 1 << 20;
    options.workers_alive = [] { return 3; };
    handler_ = std::make_unique<HttpHandler>(*store_, options);
  }

  Response call(const std::string& method, const std::string& target, const std::string& body = "",
                const std::map<std::string, std::string>& headers = {}, bool with_token = true) {
    Request request;
    request.method = method;
    request.target = target;
    request.body = body;
    if (with_token) request.headers.set("Authorization", "Bearer " + token_);
    for (const auto& [name, value] : headers) request.headers.set(name, value);
    return handler_->handle(request);
  }
  Response post(const std::string& target, const nlohmann::json& body,
                const std::map<std::string, std::string>& headers = {}) {
    return call("POST", target, body.dump(), headers);
  }

  // Uploads `bytes` through the API in chunks of `chunk` bytes; returns the blob id.
  std::string upload(const std::string& bytes, size_t chunk = 4096,
                     const std::string& name = "f.bin") {
    Response created = post("/v1/uploads", {{"name", name}, {"size", bytes.size()}});
    EXPECT_EQ(created.status, 201) << created.body;
    const std::string id = json_of(created)["id"];
    for (size_t offset = 0; offset < bytes.size(); offset += chunk) {
      size_t size = std::min(chunk, bytes.size() - offset);
      Response put = call("PUT", "/v1/uploads/" + id, bytes.substr(offset, size),
                          {{"Content-Range", "bytes " + std::to_string(offset) + "-" +
                                                 std::to_string(offset + size - 1) + "/" +
                                                 std::to_string(bytes.size())}});
      EXPECT_EQ(put.status, 200) << put.body;
    }
    Response done =
        post("/v1/uploads/" + id + "/complete", {{"sha256", keel::sha256_bytes(bytes)}});
    EXPECT_EQ(done.status, 200) << done.body;
    return json_of(done)["blob"];
  }

  nlohmann::json create_mission(const std::string& name) {
    const std::string blob = upload(valid_bundle(name));
    Response response = post("/v1/missions", {{"name", name}, {"bundle_blob", blob}});
    EXPECT_EQ(response.status, 201) << response.body;
    return json_of(response);
  }

  nlohmann::json create_job(const std::string& mission_id,
                            const std::vector<std::string>& stages = {"ingest", "refine"}) {
    Response response = post("/v1/jobs", {{"mission_id", mission_id}, {"stages", stages}});
    EXPECT_EQ(response.status, 201) << response.body;
    return json_of(response);
  }

  nlohmann::json lease() {
    Response response = post("/v1/worker/lease", {{"worker", "test:1"}, {"lease_seconds", 30}});
    EXPECT_EQ(response.status, 200) << response.body;
    return json_of(response);
  }

  TempDir dir_;
  std::unique_ptr<storage::Store> store_;
  std::unique_ptr<HttpHandler> handler_;
  std::string token_;
};

}  // namespace keel::server::testing
