// The worker protocol through the pure handler: lease, heartbeat, stages, finish.
#include "tests/server/handler_fixture.h"

namespace keel::server::testing {
namespace {

class WorkerRoutesTest : public HandlerTest {
 protected:
  void SetUp() override {
    HandlerTest::SetUp();
    mission_ = create_mission("m1");
  }
  std::string worker_path(const std::string& job_id, const std::string& rest) {
    return "/v1/worker/jobs/" + job_id + "/" + rest;
  }
  nlohmann::json mission_;
};

TEST_F(WorkerRoutesTest, NothingQueuedGives204WithoutBody) {
  Response response = post("/v1/worker/lease", {{"worker", "w:1"}, {"lease_seconds", 30}});
  EXPECT_EQ(response.status, 204);
  EXPECT_TRUE(response.body.empty());
  EXPECT_EQ(post("/v1/worker/lease", {{"worker", "w:1"}, {"lease_seconds", 0}}).status, 400);
  EXPECT_EQ(post("/v1/worker/lease", {{"worker", ""}}).status, 400);
}

TEST_F(WorkerRoutesTest, FullRunToSucceeded) {
  const std::string id = create_job(mission_["id"], {"ingest", "refine"})["id"];
  auto leased = lease();
  EXPECT_EQ(leased["job"]["id"], id);
  EXPECT_EQ(leased["mission"]["id"], mission_["id"]);
  const std::string lease_id = leased["lease_id"];
  EXPECT_EQ(json_of(call("GET", "/v1/jobs/" + id))["state"], "running");

  Response beat =
      post(worker_path(id, "heartbeat"), {{"lease_id", lease_id},
                                          {"stage", "ingest"},
                                          {"progress", 0.5},
                                          {"log", {"reading imu.csv", "1000 samples"}}});
  ASSERT_EQ(beat.status, 200) << beat.body;
  EXPECT_EQ(json_of(beat)["canceled"], false);
  EXPECT_GT(json_of(beat)["expires_at_ms"].get<int64_t>(), 0);

  auto log = json_of(call("GET", "/v1/jobs/" + id + "/log?from=0"));
  ASSERT_EQ(log["lines"].size(), 2u);
  EXPECT_EQ(log["lines"][1]["text"], "1000 samples");
  auto rest = json_of(
      call("GET", "/v1/jobs/" + id + "/log?from=" + std::to_string(log["next"].get<int64_t>())));
  EXPECT_EQ(rest["lines"].size(), 0u);
  EXPECT_EQ(call("GET", "/v1/jobs/" + id + "/log?from=-1").status, 400);
  EXPECT_EQ(call("GET", "/v1/jobs/nope/log").status, 404);

  Response stage =
      post(worker_path(id, "stages/ingest/complete"),
           {{"lease_id", lease_id}, {"report", {{"imu_samples", 1000}}}, {"seconds", 1.5}});
  EXPECT_EQ(stage.status, 204) << stage.body;
  EXPECT_EQ(post(worker_path(id, "stages/bake/complete"), {{"lease_id", lease_id}}).status, 400);

  Response done = post(worker_path(id, "complete"), {{"lease_id", lease_id}});
  ASSERT_EQ(done.status, 200) << done.body;
  EXPECT_EQ(json_of(done)["state"], "succeeded");
  EXPECT_EQ(json_of(done)["completed_stages"], nlohmann::json({"ingest"}));
}

TEST_F(WorkerRoutesTest, FailNeedsAnErrorAndRecordsIt) {
  const std::string id = create_job(mission_["id"])["id"];
  const std::string lease_id = lease()["lease_id"];
  EXPECT_EQ(post(worker_path(id, "fail"), {{"lease_id", lease_id}}).status, 400);
  Response failed =
      post(worker_path(id, "fail"), {{"lease_id", lease_id}, {"error", "imu.csv line 3: NaN"}});
  ASSERT_EQ(failed.status, 200);
  EXPECT_EQ(json_of(failed)["state"], "failed");
  EXPECT_EQ(json_of(failed)["error"], "imu.csv line 3: NaN");
  Response retried = call("POST", "/v1/jobs/" + id + "/retry");
  EXPECT_EQ(json_of(retried)["state"], "queued");
}

TEST_F(WorkerRoutesTest, WrongLeaseGivesLeaseLost) {
  const std::string id = create_job(mission_["id"])["id"];
  lease();
  Response beat = post(worker_path(id, "heartbeat"), {{"lease_id", "not-mine"}, {"progress", 0.1}});
  EXPECT_EQ(beat.status, 409);
  EXPECT_EQ(error_code_of(beat), "lease_lost");
  Response done = post(worker_path(id, "complete"), {{"lease_id", "not-mine"}});
  EXPECT_EQ(done.status, 409);
  EXPECT_EQ(error_code_of(done), "lease_lost");
  EXPECT_EQ(post(worker_path(id, "heartbeat"), {{"lease_id", "x"}, {"progress", 1.5}}).status, 400);
  EXPECT_EQ(post(worker_path("nope", "heartbeat"), {{"lease_id", "x"}}).status, 404);
}

TEST_F(WorkerRoutesTest, CancelReachesTheWorkerThroughTheHeartbeat) {
  const std::string id = create_job(mission_["id"])["id"];
  const std::string lease_id = lease()["lease_id"];
  ASSERT_EQ(call("POST", "/v1/jobs/" + id + "/cancel").status, 200);
  Response beat = post(worker_path(id, "heartbeat"), {{"lease_id", lease_id}});
  ASSERT_EQ(beat.status, 200) << beat.body;
  EXPECT_EQ(json_of(beat)["canceled"], true);
  EXPECT_EQ(error_code_of(post(worker_path(id, "complete"), {{"lease_id", lease_id}})),
            "lease_lost");
}

TEST_F(WorkerRoutesTest, ArtifactNeedsAnUploadedBlob) {
  const std::string id = create_job(mission_["id"])["id"];
  const std::string lease_id = lease()["lease_id"];
  Response missing = post(worker_path(id, "artifacts"), {{"lease_id", lease_id},
                                                         {"stage", "ingest"},
                                                         {"name", "a.json"},
                                                         {"blob", keel::sha256_bytes("never")}});
  EXPECT_EQ(missing.status, 404);
  Response bad_stage =
      post(worker_path(id, "artifacts"),
           {{"lease_id", lease_id}, {"stage", "cook"}, {"name", "a.json"}, {"blob", upload("x")}});
  EXPECT_EQ(bad_stage.status, 400);
}

}  // namespace
}  // namespace keel::server::testing
