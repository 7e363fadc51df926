// Resumable uploads and blob downloads through the pure handler, against a real store.
#include "tests/server/handler_fixture.h"

namespace keel::server::testing {
namespace {

class UploadRoutesTest : public HandlerTest {
 protected:
  std::string new_upload(int64_t size) {
    Response created = post("/v1/uploads", {{"name", "m.tar"}, {"size", size}});
    EXPECT_EQ(created.status, 201) << created.body;
    return json_of(created)["id"];
  }
  Response put(const std::string& id, const std::string& range, const std::string& body) {
    return call("PUT", "/v1/uploads/" + id, body, {{"Content-Range", range}});
  }
  int64_t committed(const std::string& id) {
    Response head = call("HEAD", "/v1/uploads/" + id);
    EXPECT_EQ(head.status, 200);
    return std::stoll(head.headers.get("Upload-Offset").value_or("-1"));
  }
};

TEST_F(UploadRoutesTest, CreateAnswersTheUpload) {
  Response created = post("/v1/uploads", {{"name", "m.tar"}, {"size", 10}});
  ASSERT_EQ(created.status, 201);
  auto body = json_of(created);
  EXPECT_EQ(body["name"], "m.tar");
  EXPECT_EQ(body["size"], 10);
  EXPECT_EQ(body["offset"], 0);
  EXPECT_EQ(body["blob"], "");
  EXPECT_EQ(created.headers.get("Content-Type"), "application/json");
}

TEST_F(UploadRoutesTest, CreateRejectsBadBodiesNamingTheField) {
  Response bad_json = call("POST", "/v1/uploads", "{\"name\": ");
  EXPECT_EQ(bad_json.status, 400);
  EXPECT_EQ(error_code_of(bad_json), "bad_json");

  Response missing = post("/v1/uploads", {{"name", "m.tar"}});
  EXPECT_EQ(missing.status, 400);
  EXPECT_EQ(error_code_of(missing), "invalid_field");
  EXPECT_NE(json_of(missing)["error"]["message"].get<std::string>().find("size"),
            std::string::npos);

  Response typo = post("/v1/uploads", {{"name", "m.tar"}, {"size", 3}, {"sise", 3}});
  EXPECT_EQ(typo.status, 400);
  EXPECT_NE(typo.body.find("sise"), std::string::npos);

  Response negative = post("/v1/uploads", {{"name", "m.tar"}, {"size", -1}});
  EXPECT_EQ(negative.status, 400);
}

TEST_F(UploadRoutesTest, ChunksCommitInOrderAndCompleteToTheRightBlob) {
  const std::string bytes = random_bytes(10000, 1);
  const std::string id = new_upload(10000);
  EXPECT_EQ(put(id, "bytes 0-3999/10000", bytes.substr(0, 4000)).status, 200);
  EXPECT_EQ(committed(id), 4000);
  Response second = put(id, "bytes 4000-9999/10000", bytes.substr(4000));
  ASSERT_EQ(second.status, 200) << second.body;
  EXPECT_EQ(json_of(second)["offset"], 10000);
  EXPECT_EQ(second.headers.get("Upload-Offset"), "10000");
  Response got = call("GET", "/v1/uploads/" + id);
  EXPECT_EQ(json_of(got)["offset"], 10000);
  EXPECT_EQ(call("HEAD", "/v1/uploads/" + id).headers.get("Upload-Length"), "10000");

  const std::string sha = keel::sha256_bytes(bytes);
  Response done = post("/v1/uploads/" + id + "/complete", {{"sha256", sha}});
  ASSERT_EQ(done.status, 200) << done.body;
  EXPECT_EQ(json_of(done)["blob"], sha);
  EXPECT_EQ(json_of(done)["size"], 10000);

  Response blob = call("GET", "/v1/blobs/" + sha);
  ASSERT_EQ(blob.status, 200);
  ASSERT_TRUE(blob.file.has_value());
  EXPECT_EQ(read_region(*blob.file), bytes);
  EXPECT_EQ(keel::sha256_file(blob.file->path), sha);
}

TEST_F(UploadRoutesTest, OutOfOrderOrOverlappingChunksGive409WithTheOffset) {
  const std::string bytes = random_bytes(100, 2);
  const std::string id = new_upload(100);
  Response ahead = put(id, "bytes 10-19/100", bytes.substr(10, 10));
  EXPECT_EQ(ahead.status, 409);
  EXPECT_EQ(error_code_of(ahead), "offset_mismatch");
  EXPECT_EQ(ahead.headers.get("Upload-Offset"), "0");

  ASSERT_EQ(put(id, "bytes 0-49/100", bytes.substr(0, 50)).status, 200);
  Response overlap = put(id, "bytes 40-59/100", bytes.substr(40, 20));
  EXPECT_EQ(overlap.status, 409);
  EXPECT_EQ(overlap.headers.get("Upload-Offset"), "50");
  EXPECT_NE(overlap.body.find("50"), std::string::npos);
  Response repeat = put(id, "bytes 0-49/100", bytes.substr(0, 50));  // a resent chunk
  EXPECT_EQ(repeat.status, 409);
  EXPECT_EQ(committed(id), 50);
}

TEST_F(UploadRoutesTest, MalformedOrInconsistentRangesGive416AndCommitNothing) {
  const std::string id = new_upload(10);
  const std::string five = "hello";
  for (const char* range :
       {"bytes 0-4", "bytes=0-4/10", "bytes 4-0/10", "bytes 0-10/10", "bytes a-4/10", "bytes 0-4/*",
        "bytes  0-4/10", "items 0-4/10", "bytes -4/10", "bytes 0-4/10, 5-9"}) {
    Response response = put(id, range, five);
    EXPECT_EQ(response.status, 416) << range;
    EXPECT_EQ(error_code_of(response), "bad_range") << range;
  }
  Response missing = call("PUT", "/v1/uploads/" + id, five);
  EXPECT_EQ(missing.status, 416);
  Response short_body = put(id, "bytes 0-4/10", "hell");
  EXPECT_EQ(short_body.status, 416);
  Response wrong_total = put(id, "bytes 0-4/11", five);
  EXPECT_EQ(wrong_total.status, 416);
  EXPECT_NE(wrong_total.body.find("announced size 10"), std::string::npos) << wrong_total.body;
  EXPECT_EQ(committed(id), 0);
}

TEST_F(UploadRoutesTest, WrongShaGives422AndKeepsNothing) {
  const std::string bytes = random_bytes(64, 3);
  const std::string id = new_upload(64);
  ASSERT_EQ(put(id, "bytes 0-63/64", bytes).status, 200);
  const std::string wrong = keel::sha256_bytes("something else");
  Response done = post("/v1/uploads/" + id + "/complete", {{"sha256", wrong}});
  EXPECT_EQ(done.status, 422);
  EXPECT_EQ(error_code_of(done), "sha256_mismatch");
  EXPECT_EQ(call("GET", "/v1/uploads/" + id).status, 404);
  EXPECT_EQ(call("GET", "/v1/blobs/" + wrong).status, 404);
  EXPECT_EQ(call("GET", "/v1/blobs/" + keel::sha256_bytes(bytes)).status, 404);
  EXPECT_EQ(store_->metrics().blobs, 0);
}

TEST_F(UploadRoutesTest, IncompleteUploadGivesSizeMismatch) {
  const std::string bytes = random_bytes(64, 4);
  const std::string id = new_upload(64);
  ASSERT_EQ(put(id, "bytes 0-31/64", bytes.substr(0, 32)).status, 200);
  Response done =
      post("/v1/uploads/" + id + "/complete", {{"sha256", keel::sha256_bytes(bytes)}});
  EXPECT_EQ(done.status, 422);
  EXPECT_EQ(error_code_of(done), "size_mismatch");
}

TEST_F(UploadRoutesTest, CompleteRejectsMalformedSha) {
  const std::string id = new_upload(1);
  Response done = post("/v1/uploads/" + id + "/complete", {{"sha256", "ABC"}});
  EXPECT_EQ(done.status, 400);
  EXPECT_EQ(error_code_of(done), "invalid_field");
  EXPECT_EQ(call("GET", "/v1/uploads/" + id).status, 200);  // still there
}

TEST_F(UploadRoutesTest, IdenticalContentGivesTheSameBlob) {
  const std::string bytes = random_bytes(5000, 5);
  const std::string first = upload(bytes, 1000);
  const std::string second = upload(bytes, 3000);
  EXPECT_EQ(first, second);
  EXPECT_EQ(first, keel::sha256_bytes(bytes));
  EXPECT_EQ(store_->metrics().blobs, 1);
}

TEST_F(UploadRoutesTest, EmptyUploadCompletes) {
  const std::string id = new_upload(0);
  Response done = post("/v1/uploads/" + id + "/complete", {{"sha256", keel::sha256_bytes("")}});
  ASSERT_EQ(done.status, 200) << done.body;
  Response blob = call("GET", "/v1/blobs/" + keel::sha256_bytes(""));
  ASSERT_EQ(blob.status, 200);
  EXPECT_EQ(blob.file->length, 0u);
  EXPECT_EQ(
      call("GET", "/v1/blobs/" + keel::sha256_bytes(""), "", {{"Range", "bytes=0-"}}).status,
      416);
}

TEST_F(UploadRoutesTest, DeleteAndUnknownIds) {
  const std::string id = new_upload(5);
  EXPECT_EQ(call("DELETE", "/v1/uploads/" + id).status, 204);
  EXPECT_EQ(call("GET", "/v1/uploads/" + id).status, 404);
  EXPECT_EQ(call("HEAD", "/v1/uploads/" + id).status, 404);
  Response put_missing = put(id, "bytes 0-4/5", "hello");
  EXPECT_EQ(put_missing.status, 404);
  EXPECT_EQ(error_code_of(put_missing), "not_found");
  EXPECT_EQ(call("GET", "/v1/blobs/not-a-sha").status, 404);
}

}  // namespace
}  // namespace keel::server::testing
