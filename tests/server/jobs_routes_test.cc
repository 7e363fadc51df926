// Jobs, logs, reprocessing and artifact downloads through the pure handler.
#include "tests/server/handler_fixture.h"

#include <set>

#include "server/byte_range.h"

namespace keel::server::testing {
namespace {

class JobRoutesTest : public HandlerTest {};

TEST_F(JobRoutesTest, CreateGetAndList) {
  auto mission = create_mission("m1");
  auto job = create_job(mission["id"]);
  EXPECT_EQ(job["state"], "queued");
  EXPECT_EQ(job["mission_id"], mission["id"]);
  EXPECT_EQ(job["stages"], nlohmann::json({"ingest", "refine"}));

  Response got = call("GET", "/v1/jobs/" + job["id"].get<std::string>());
  ASSERT_EQ(got.status, 200);
  EXPECT_EQ(json_of(got)["id"], job["id"]);

  auto second = create_job(mission["id"], {"ingest"});
  auto jobs = json_of(call("GET", "/v1/jobs"))["jobs"];
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs[0]["id"], second["id"]);  // newest first
  EXPECT_EQ(json_of(call("GET", "/v1/jobs?state=queued"))["jobs"].size(), 2u);
  EXPECT_EQ(json_of(call("GET", "/v1/jobs?state=running"))["jobs"].size(), 0u);
  EXPECT_EQ(json_of(call("GET", "/v1/jobs?mission_id=" + mission["id"].get<std::string>()))["jobs"]
                .size(),
            2u);
  EXPECT_EQ(json_of(call("GET", "/v1/jobs?mission_id=other"))["jobs"].size(), 0u);
  EXPECT_EQ(json_of(call("GET", "/v1/jobs?limit=1"))["jobs"].size(), 1u);

  Response bad_state = call("GET", "/v1/jobs?state=sleeping");
  EXPECT_EQ(bad_state.status, 400);
  EXPECT_NE(bad_state.body.find("sleeping"), std::string::npos);
  EXPECT_EQ(call("GET", "/v1/jobs?limit=zero").status, 400);
  EXPECT_EQ(call("GET", "/v1/jobs/unknown").status, 404);
}

TEST_F(JobRoutesTest, CreateRejectsBadRequests) {
  auto mission = create_mission("m1");
  Response unknown_mission = post("/v1/jobs", {{"mission_id", "nope"}, {"stages", {"ingest"}}});
  EXPECT_EQ(unknown_mission.status, 404);
  Response bad_stage = post("/v1/jobs", {{"mission_id", mission["id"]}, {"stages", {"bake"}}});
  EXPECT_EQ(bad_stage.status, 400);
  EXPECT_EQ(error_code_of(bad_stage), "invalid_field");
  EXPECT_NE(bad_stage.body.find("stages"), std::string::npos);
  Response wrong_type = post("/v1/jobs", {{"mission_id", 7}, {"stages", {"ingest"}}});
  EXPECT_EQ(wrong_type.status, 400);
  EXPECT_NE(wrong_type.body.find("mission_id"), std::string::npos);
}

// A job's extrinsic overrides (docs/calibration.md): stored as given, refused naming the path.
TEST_F(JobRoutesTest, CalibrationOptionsAreCheckedAtTheDoor) {
  auto mission = create_mission("m1");
  const nlohmann::json pose = {{"xyz_m", {0.1, 0, 0.4}}, {"rpy_deg", {0, 90, 0}}};
  Response good =
      post("/v1/jobs", {{"mission_id", mission["id"]},
                        {"stages", {"ingest", "map"}},
                        {"options", {{"calibration", {{"lidar_v", {{"T_body_sensor", pose}}}}}}}});
  ASSERT_EQ(good.status, 201) << good.body;
  EXPECT_EQ(json_of(good)["options"]["calibration"]["lidar_v"]["T_body_sensor"], pose);

  Response bad =
      post("/v1/jobs",
           {{"mission_id", mission["id"]},
            {"stages", {"ingest"}},
            {"options",
             {{"calibration",
               {{"sonar", {{"T_body_sensor", {{"xyz_m", {1, 2}}, {"rpy_deg", {0, 0, 0}}}}}}}}}}});
  EXPECT_EQ(bad.status, 400);
  EXPECT_EQ(error_code_of(bad), "invalid_field");
  EXPECT_NE(bad.body.find("options.calibration.sonar.T_body_sensor.xyz_m: expected 3 numbers"),
            std::string::npos)
      << bad.body;
  Response bad_key =
      post("/v1/reprocess", {{"mission_ids", {mission["id"]}},
                             {"stages", {"ingest"}},
                             {"options", {{"calibration", {{"sonar", {{"T_sonar", pose}}}}}}}});
  EXPECT_EQ(bad_key.status, 400);
  EXPECT_NE(bad_key.body.find("options.calibration.sonar.T_sonar: expected T_body_sensor or "
                              "T_<reference>_sonar"),
            std::string::npos)
      << bad_key.body;
}

TEST_F(JobRoutesTest, IdempotencyKeyReturnsTheFirstJob) {
  auto mission = create_mission("m1");
  nlohmann::json body = {{"mission_id", mission["id"]}, {"stages", {"ingest"}}};
  Response first = post("/v1/jobs", body, {{"Idempotency-Key", "submit-42"}});
  Response again = post("/v1/jobs", body, {{"Idempotency-Key", "submit-42"}});
  ASSERT_EQ(first.status, 201);
  ASSERT_EQ(again.status, 200);
  EXPECT_EQ(json_of(first)["id"], json_of(again)["id"]);
  Response other = post("/v1/jobs", body, {{"Idempotency-Key", "submit-43"}});
  EXPECT_EQ(other.status, 201);
  EXPECT_NE(json_of(other)["id"], json_of(first)["id"]);
  Response no_key_1 = post("/v1/jobs", body);
  Response no_key_2 = post("/v1/jobs", body);
  EXPECT_NE(json_of(no_key_1)["id"], json_of(no_key_2)["id"]);
  EXPECT_EQ(json_of(call("GET", "/v1/jobs"))["jobs"].size(), 4u);
  EXPECT_EQ(post("/v1/jobs", body, {{"Idempotency-Key", std::string(300, 'k')}}).status, 400);
}

TEST_F(JobRoutesTest, CancelAndRetryFollowTheStateRules) {
  auto mission = create_mission("m1");
  const std::string id = create_job(mission["id"])["id"];
  Response retry_queued = post("/v1/jobs/" + id + "/retry", nlohmann::json::object());
  EXPECT_EQ(retry_queued.status, 409);
  EXPECT_EQ(error_code_of(retry_queued), "conflict");

  Response canceled = call("POST", "/v1/jobs/" + id + "/cancel");
  ASSERT_EQ(canceled.status, 200);
  EXPECT_EQ(json_of(canceled)["state"], "canceled");
  EXPECT_EQ(call("POST", "/v1/jobs/" + id + "/cancel").status, 409);

  Response retried = call("POST", "/v1/jobs/" + id + "/retry");
  ASSERT_EQ(retried.status, 200);
  EXPECT_EQ(json_of(retried)["state"], "queued");
  EXPECT_EQ(call("POST", "/v1/jobs/unknown/cancel").status, 404);
}

TEST_F(JobRoutesTest, ReprocessMakesOneJobPerMatchingMission) {
  auto a = create_mission("bridge-a");
  auto b = create_mission("bridge-b");
  create_mission("hull-c");
  Response response = post("/v1/reprocess", {{"name_prefix", "bridge-"},
                                             {"stages", {"ingest", "map"}},
                                             {"options", {{"map", {{"voxel_m", 0.1}}}}}});
  ASSERT_EQ(response.status, 201) << response.body;
  auto jobs = json_of(response)["jobs"];
  ASSERT_EQ(jobs.size(), 2u);
  std::set<std::string> missions;
  for (const auto& job : jobs) {
    missions.insert(job["mission_id"]);
    EXPECT_EQ(job["stages"], nlohmann::json({"ingest", "map"}));
    EXPECT_EQ(job["options"]["map"]["voxel_m"], 0.1);
  }
  EXPECT_EQ(missions, (std::set<std::string>{a["id"], b["id"]}));

  Response by_id = post("/v1/reprocess", {{"mission_ids", {a["id"]}}, {"stages", {"ingest"}}});
  ASSERT_EQ(by_id.status, 201);
  EXPECT_EQ(json_of(by_id)["jobs"].size(), 1u);

  const size_t before = json_of(call("GET", "/v1/jobs"))["jobs"].size();
  Response unknown =
      post("/v1/reprocess", {{"mission_ids", {a["id"], "nope"}}, {"stages", {"ingest"}}});
  EXPECT_EQ(unknown.status, 404);
  EXPECT_NE(unknown.body.find("mission_ids[1]"), std::string::npos);
  EXPECT_EQ(json_of(call("GET", "/v1/jobs"))["jobs"].size(), before);  // nothing made

  Response both = post("/v1/reprocess",
                       {{"mission_ids", {a["id"]}}, {"name_prefix", "b"}, {"stages", {"ingest"}}});
  EXPECT_EQ(both.status, 400);
}

// A job with one registered artifact of `bytes`; returns the artifact id.
class ArtifactRoutesTest : public HandlerTest {
 protected:
  void SetUp() override {
    HandlerTest::SetUp();
    bytes_ = random_bytes(100'000, 7);
    auto mission = create_mission("m1");
    job_id_ = create_job(mission["id"])["id"];
    auto leased = lease();
    const std::string blob = upload(bytes_, 30'000);
    Response registered =
        post("/v1/worker/jobs/" + job_id_ + "/artifacts", {{"lease_id", leased["lease_id"]},
                                                           {"stage", "ingest"},
                                                           {"name", "report.json"},
                                                           {"blob", blob}});
    ASSERT_EQ(registered.status, 201) << registered.body;
    artifact_id_ = json_of(registered)["id"];
    sha_ = blob;
  }

  Response get(const std::map<std::string, std::string>& headers = {}) {
    return call("GET", "/v1/artifacts/" + artifact_id_, "", headers);
  }

  std::string bytes_, job_id_, artifact_id_, sha_;
};

TEST_F(ArtifactRoutesTest, ListsAndServesTheWholeFile) {
  auto artifacts = json_of(call("GET", "/v1/jobs/" + job_id_ + "/artifacts"))["artifacts"];
  ASSERT_EQ(artifacts.size(), 1u);
  EXPECT_EQ(artifacts[0]["sha256"], sha_);
  EXPECT_EQ(artifacts[0]["size"], 100'000);
  EXPECT_EQ(call("GET", "/v1/jobs/unknown/artifacts").status, 404);

  Response full = get();
  ASSERT_EQ(full.status, 200);
  EXPECT_EQ(full.headers.get("ETag"), "\"" + sha_ + "\"");
  EXPECT_EQ(full.headers.get("Accept-Ranges"), "bytes");
  EXPECT_EQ(full.headers.get("Content-Type"), "application/json");
  ASSERT_TRUE(full.file.has_value());
  EXPECT_EQ(read_region(*full.file), bytes_);
  EXPECT_EQ(call("GET", "/v1/artifacts/unknown").status, 404);
}

TEST_F(ArtifactRoutesTest, RangesAreByteExact) {
  struct Case {
    std::string range;
    size_t offset, length;
  };
  const size_t n = bytes_.size();
  for (const Case& c : std::vector<Case>{{"bytes=0-0", 0, 1},
                                         {"bytes=10-19", 10, 10},
                                         {"bytes=99990-", 99990, 10},
                                         {"bytes=-7", n - 7, 7},
                                         {"bytes=-1000000", 0, n},
                                         {"bytes=50000-999999", 50000, n - 50000}}) {
    Response part = get({{"Range", c.range}});
    ASSERT_EQ(part.status, 206) << c.range;
    ASSERT_TRUE(part.file.has_value());
    EXPECT_EQ(read_region(*part.file), bytes_.substr(c.offset, c.length)) << c.range;
    EXPECT_EQ(part.headers.get("Content-Range"), "bytes " + std::to_string(c.offset) + "-" +
                                                     std::to_string(c.offset + c.length - 1) + "/" +
                                                     std::to_string(n))
        << c.range;
  }
}

TEST_F(ArtifactRoutesTest, UnsatisfiableOrMalformedRangesGive416) {
  for (const char* range : {"bytes=100000-", "bytes=200000-300000", "bytes=-0", "bytes=5-2",
                            "bytes=0-1,5-6", "lines=1-2", "bytes=x-"}) {
    Response response = get({{"Range", range}});
    EXPECT_EQ(response.status, 416) << range;
    EXPECT_EQ(error_code_of(response), "bad_range") << range;
    EXPECT_EQ(response.headers.get("Content-Range"), "bytes */100000") << range;
    EXPECT_FALSE(response.file.has_value());
  }
}

TEST_F(ArtifactRoutesTest, IfNoneMatchGives304AndIfRangeGuardsRanges) {
  Response cached = get({{"If-None-Match", "\"" + sha_ + "\""}});
  EXPECT_EQ(cached.status, 304);
  EXPECT_TRUE(cached.body.empty());
  EXPECT_FALSE(cached.file.has_value());
  EXPECT_EQ(get({{"If-None-Match", "\"other\", \"" + sha_ + "\""}}).status, 304);
  EXPECT_EQ(get({{"If-None-Match", "*"}}).status, 304);
  EXPECT_EQ(get({{"If-None-Match", "\"" + std::string(64, '0') + "\""}}).status, 200);

  EXPECT_EQ(get({{"Range", "bytes=0-9"}, {"If-Range", "\"" + sha_ + "\""}}).status, 206);
  EXPECT_EQ(get({{"Range", "bytes=0-9"}, {"If-Range", "\"stale\""}}).status, 200);
}

TEST_F(ArtifactRoutesTest, BlobRouteServesTheSameBytes) {
  Response part = call("GET", "/v1/blobs/" + sha_, "", {{"Range", "bytes=1000-1999"}});
  ASSERT_EQ(part.status, 206);
  EXPECT_EQ(read_region(*part.file), bytes_.substr(1000, 1000));
}

}  // namespace
}  // namespace keel::server::testing
