// The worker protocol with a fake clock: leases, heartbeats, expiry, cancel, finish, retry.
#include <gtest/gtest.h>

#include "store_fixture.h"

namespace keel::storage {
namespace {

using testing::StoreTest;

class LeaseTest : public StoreTest {
 protected:
  proto::Heartbeat beat(const proto::Lease& lease, const std::string& stage, double progress,
                        std::vector<std::string> log = {}) {
    return {lease.lease_id, stage, progress, std::move(log)};
  }
  proto::StageCompletion completion(const proto::Lease& lease, double seconds,
                                    nlohmann::json report = nlohmann::json::object()) {
    return {lease.lease_id, std::move(report), seconds};
  }
};

TEST_P(LeaseTest, NothingQueuedGivesNoLease) { EXPECT_FALSE(store_->lease_job({"w", 30})); }

TEST_P(LeaseTest, OldestQueuedFirstWithMissionAndExpiry) {
  const proto::Mission mission = make_mission();
  const proto::Job first = store_->create_job(job_request(mission), "");
  clock_.advance_ms(1);
  const proto::Job second = store_->create_job(job_request(mission), "");
  clock_.advance_ms(1000);
  const proto::Lease lease = this->lease("host:7", 20);
  EXPECT_EQ(lease.job.id, first.id);
  EXPECT_EQ(lease.lease_id.rfind("l_", 0), 0u);
  EXPECT_EQ(lease.expires_at_ms, clock_.now_ms() + 20'000);
  EXPECT_EQ(lease.job.state, proto::JobState::kRunning);
  EXPECT_EQ(lease.job.attempts, 1);
  EXPECT_EQ(lease.job.started_at_ms, clock_.now_ms());
  EXPECT_EQ(lease.mission.id, mission.id);
  EXPECT_EQ(lease.mission.bundle_blob, mission.bundle_blob);
  EXPECT_TRUE(lease.completed.empty());
  EXPECT_EQ(this->lease().job.id, second.id);
  EXPECT_FALSE(store_->lease_job({"w", 30}));
}

TEST_P(LeaseTest, HeartbeatExtendsLeaseAndRecordsProgressAndLog) {
  store_->create_job(job_request(make_mission()), "");
  const proto::Lease lease = this->lease("w", 30);
  clock_.advance_ms(25'000);
  const proto::HeartbeatReply reply =
      store_->heartbeat(lease.job.id, beat(lease, "refine", 0.25, {"refining", "iter 1"}));
  EXPECT_FALSE(reply.canceled);
  EXPECT_EQ(reply.expires_at_ms, clock_.now_ms() + 30'000);
  const proto::Job job = store_->get_job(lease.job.id);
  EXPECT_EQ(job.stage, "refine");
  EXPECT_DOUBLE_EQ(job.progress, 0.25);
  const proto::LogPage log = store_->read_log(job.id, 0, 100);
  ASSERT_EQ(log.lines.size(), 2u);
  EXPECT_EQ(log.lines[1].text, "iter 1");
  // Past the original expiry but within the extended one: nobody else can take the job.
  clock_.advance_ms(20'000);
  EXPECT_FALSE(store_->lease_job({"other", 30}));
  EXPECT_THROW(store_->heartbeat(lease.job.id, beat(lease, "bake", 0.5)), Invalid);
}

TEST_P(LeaseTest, ExpiredLeaseIsReleasedAndOldLeaseGetsConflict) {
  store_->create_job(job_request(make_mission()), "");
  const proto::Lease first = lease("worker-a", 10);
  clock_.advance_ms(10'001);
  const proto::Lease second = lease("worker-b", 10);
  EXPECT_EQ(second.job.id, first.job.id);
  EXPECT_NE(second.lease_id, first.lease_id);
  EXPECT_EQ(second.job.attempts, 2);
  EXPECT_EQ(second.job.started_at_ms, first.job.started_at_ms);
  try {
    store_->heartbeat(first.job.id, beat(first, "ingest", 0.5));
    FAIL() << "expected LeaseLost";
  } catch (const LeaseLost& error) {
    const std::string text = error.what();
    EXPECT_NE(text.find(first.job.id), std::string::npos) << text;
    EXPECT_NE(text.find(first.lease_id), std::string::npos) << text;
  }
  EXPECT_THROW(store_->finish_job(first.job.id, {first.lease_id, ""}, true), Conflict);
  EXPECT_THROW(store_->complete_stage(first.job.id, "ingest", completion(first, 1.0)), Conflict);
  // The new holder is unaffected.
  EXPECT_FALSE(store_->heartbeat(second.job.id, beat(second, "ingest", 0.1)).canceled);
  const auto log = store_->read_log(first.job.id, 0, 100);
  ASSERT_FALSE(log.lines.empty());
  EXPECT_NE(log.lines[0].text.find("worker-a"), std::string::npos);
}

TEST_P(LeaseTest, ThirdExpiryFailsTheJob) {
  const proto::Job job = store_->create_job(job_request(make_mission()), "");
  for (int attempt = 1; attempt <= 3; ++attempt) {
    const proto::Lease lease = this->lease("w" + std::to_string(attempt), 5);
    EXPECT_EQ(lease.job.id, job.id);
    EXPECT_EQ(lease.job.attempts, attempt);
    clock_.advance_ms(5'000);  // expires_at <= now: expired
  }
  EXPECT_FALSE(store_->lease_job({"w4", 5}));  // failed instead of leased a fourth time
  const proto::Job failed = store_->get_job(job.id);
  EXPECT_EQ(failed.state, proto::JobState::kFailed);
  EXPECT_EQ(failed.error, "lease expired 3 times (last worker: w3)");
  EXPECT_EQ(failed.attempts, 3);
  EXPECT_EQ(failed.finished_at_ms, clock_.now_ms());
}

TEST_P(LeaseTest, StagesAndArtifactsThenSucceed) {
  store_->create_job(job_request(make_mission()), "");
  const proto::Lease lease = this->lease();
  const std::string job_id = lease.job.id;
  const std::string blob = store_->put_blob("trajectory");
  const proto::Artifact artifact =
      store_->add_artifact(job_id, {lease.lease_id, "refine", "trajectory_refined.tum", blob});
  EXPECT_EQ(artifact.id.rfind("a_", 0), 0u);
  EXPECT_EQ(artifact.size, 10);
  EXPECT_EQ(store_->get_artifact(artifact.id).sha256, blob);
  store_->complete_stage(job_id, "ingest", completion(lease, 1.5, {{"frames", 10}}));
  store_->complete_stage(job_id, "refine", completion(lease, 2.5));
  store_->complete_stage(job_id, "ingest", completion(lease, 1.5, {{"frames", 10}}));  // repeat
  proto::Job job = store_->get_job(job_id);
  EXPECT_EQ(job.completed_stages, (std::vector<std::string>{"ingest", "refine"}));
  EXPECT_DOUBLE_EQ(job.stage_seconds.at("refine"), 2.5);
  EXPECT_THROW(store_->complete_stage(job_id, "ba", completion(lease, 1.0)), Invalid);
  job = store_->finish_job(job_id, {lease.lease_id, ""}, true);
  EXPECT_EQ(job.state, proto::JobState::kSucceeded);
  EXPECT_EQ(job.finished_at_ms, clock_.now_ms());
  EXPECT_THROW(store_->finish_job(job_id, {lease.lease_id, ""}, true), Conflict);
  EXPECT_THROW(store_->heartbeat(job_id, beat(lease, "map", 1.0)), LeaseLost);
  EXPECT_THROW(store_->cancel_job(job_id), Conflict);
  EXPECT_THROW(store_->retry_job(job_id), Conflict);
}

TEST_P(LeaseTest, ArtifactRulesAndReplacement) {
  store_->create_job(job_request(make_mission()), "");
  const proto::Lease lease = this->lease();
  const std::string job_id = lease.job.id;
  const std::string missing(64, 'e');
  try {
    store_->add_artifact(job_id, {lease.lease_id, "map", "map.drc", missing});
    FAIL() << "expected NotFound";
  } catch (const NotFound& error) {
    EXPECT_NE(std::string(error.what()).find(missing), std::string::npos);
  }
  const std::string v1 = store_->put_blob("map v1");
  const std::string v2 = store_->put_blob("map v2, longer");
  EXPECT_THROW(store_->add_artifact(job_id, {"l_0000000000000000", "map", "map.drc", v1}),
               LeaseLost);
  EXPECT_THROW(store_->add_artifact(job_id, {lease.lease_id, "map", "../map.drc", v1}), Invalid);
  EXPECT_THROW(store_->add_artifact(job_id, {lease.lease_id, "bake", "map.drc", v1}), Invalid);
  const proto::Artifact first =
      store_->add_artifact(job_id, {lease.lease_id, "map", "map.drc", v1});
  store_->add_artifact(job_id, {lease.lease_id, "refine", "map.drc", v1});  // other stage: kept
  const proto::Artifact second =
      store_->add_artifact(job_id, {lease.lease_id, "map", "map.drc", v2});
  const auto artifacts = store_->list_artifacts(job_id);
  ASSERT_EQ(artifacts.size(), 2u);
  EXPECT_EQ(artifacts[0].stage, "refine");
  EXPECT_EQ(artifacts[1].id, second.id);
  EXPECT_EQ(artifacts[1].sha256, v2);
  EXPECT_EQ(artifacts[1].size, 14);
  EXPECT_THROW(store_->get_artifact(first.id), NotFound);
  EXPECT_THROW(store_->list_artifacts("j_0000000000000000"), NotFound);
}

TEST_P(LeaseTest, CancelWhileRunning) {
  store_->create_job(job_request(make_mission()), "");
  const proto::Lease lease = this->lease();
  const proto::Job canceled = store_->cancel_job(lease.job.id);
  EXPECT_EQ(canceled.state, proto::JobState::kCanceled);
  const proto::HeartbeatReply reply = store_->heartbeat(lease.job.id, beat(lease, "map", 0.5));
  EXPECT_TRUE(reply.canceled);
  try {
    store_->finish_job(lease.job.id, {lease.lease_id, ""}, true);
    FAIL() << "expected Conflict";
  } catch (const Conflict& error) {
    EXPECT_NE(std::string(error.what()).find(lease.job.id), std::string::npos);
  }
  EXPECT_THROW(store_->complete_stage(lease.job.id, "ingest", completion(lease, 1.0)), Conflict);
  EXPECT_EQ(store_->get_job(lease.job.id).state, proto::JobState::kCanceled);
  EXPECT_FALSE(store_->lease_job({"w", 30}));
}

TEST_P(LeaseTest, FailThenRetryKeepsCompletedStagesAndArtifacts) {
  store_->create_job(job_request(make_mission(), {"ingest", "refine", "map"}), "");
  const proto::Lease first = lease("w1");
  const std::string job_id = first.job.id;
  const std::string blob = store_->put_blob("ingested");
  store_->add_artifact(job_id, {first.lease_id, "ingest", "ingest.json", blob});
  store_->complete_stage(job_id, "ingest", completion(first, 3.0, {{"imu_samples", 1200}}));
  store_->complete_stage(job_id, "refine", completion(first, 4.0));
  proto::Job failed = store_->finish_job(job_id, {first.lease_id, "map: no scans"}, false);
  EXPECT_EQ(failed.state, proto::JobState::kFailed);
  EXPECT_EQ(failed.error, "map: no scans");

  const proto::Job queued = store_->retry_job(job_id);
  EXPECT_EQ(queued.state, proto::JobState::kQueued);
  EXPECT_EQ(queued.error, "");
  EXPECT_EQ(queued.finished_at_ms, 0);
  EXPECT_EQ(queued.completed_stages, (std::vector<std::string>{"ingest", "refine"}));

  const proto::Lease second = lease("w2");
  EXPECT_EQ(second.job.id, job_id);
  EXPECT_EQ(second.job.attempts, 2);
  ASSERT_EQ(second.completed.size(), 2u);
  EXPECT_EQ(second.completed[0].stage, "ingest");  // pipeline order
  EXPECT_EQ(second.completed[0].report["imu_samples"], 1200);
  EXPECT_DOUBLE_EQ(second.completed[0].seconds, 3.0);
  ASSERT_EQ(second.completed[0].artifacts.size(), 1u);
  EXPECT_EQ(second.completed[0].artifacts[0].name, "ingest.json");
  EXPECT_EQ(second.completed[0].artifacts[0].sha256, blob);
  EXPECT_EQ(second.completed[1].stage, "refine");
  EXPECT_TRUE(second.completed[1].artifacts.empty());
  // The first attempt's lease is dead.
  EXPECT_THROW(store_->heartbeat(job_id, beat(first, "map", 0.1)), LeaseLost);
  store_->complete_stage(job_id, "map", completion(second, 5.0));
  EXPECT_EQ(store_->finish_job(job_id, {second.lease_id, ""}, true).completed_stages.size(), 3u);
}

TEST_P(LeaseTest, RetryAfterCancelRequeues) {
  store_->create_job(job_request(make_mission()), "");
  const proto::Lease first = lease();
  store_->cancel_job(first.job.id);
  EXPECT_EQ(store_->retry_job(first.job.id).state, proto::JobState::kQueued);
  EXPECT_THROW(store_->heartbeat(first.job.id, beat(first, "", 0.0)), LeaseLost);
  EXPECT_EQ(lease().job.id, first.job.id);
}

KEEL_STORE_TEST_SUITE(LeaseTest);

}  // namespace
}  // namespace keel::storage
