// Projects, token roles, reprocess batches, lease release/requeue, the change feed and the
// queue summary (storage/store.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>

#include "storage/migrations.h"
#include "core/sha256.h"
#include "storage/sqlite_db.h"
#include "store_fixture.h"

namespace keel::storage {
namespace {

using ProjectTest = testing::StoreTest;

TokenSpec spec(proto::Role role, const std::string& project, int64_t expires_at_ms = 0) {
  TokenSpec out;
  out.label = proto::to_string(role) + "@" + project;
  out.role = role;
  out.project = project;
  out.expires_at_ms = expires_at_ms;
  return out;
}

proto::Mission mission_in(Store& store, const std::string& project, const std::string& name) {
  proto::MissionRequest request;
  request.name = name;
  request.bundle_blob = store.put_blob("bundle of " + name);
  request.project = project;
  return store.create_mission(request);
}

TEST_P(ProjectTest, TokensCarryRoleProjectExpiryAndRevocation) {
  const proto::TokenInfo submitter =
      store_->add_token("tok-submitter", spec(proto::Role::kSubmitter, "harbour"));
  EXPECT_EQ(submitter.role, proto::Role::kSubmitter);
  EXPECT_EQ(submitter.project, "harbour");
  EXPECT_EQ(submitter.id.rfind("t_", 0), 0u);
  auto checked = store_->check_token("tok-submitter");
  ASSERT_TRUE(checked);
  EXPECT_EQ(checked->id, submitter.id);
  EXPECT_TRUE(checked->reaches("harbour"));
  EXPECT_FALSE(checked->reaches("default"));

  // The project came into being with the token.
  auto projects = store_->list_projects();
  ASSERT_EQ(projects.size(), 2u);
  EXPECT_EQ(projects[0].name, "default");
  EXPECT_EQ(projects[1].name, "harbour");

  store_->add_token("tok-viewer", spec(proto::Role::kViewer, "harbour", clock_.now_ms() + 1000));
  EXPECT_TRUE(store_->check_token("tok-viewer"));
  clock_.advance_ms(1000);
  EXPECT_FALSE(store_->check_token("tok-viewer")) << "expired at its expiry time";

  const proto::TokenInfo revoked = store_->revoke_token(submitter.id);
  EXPECT_EQ(revoked.revoked_at_ms, clock_.now_ms());
  EXPECT_FALSE(store_->check_token("tok-submitter"));
  EXPECT_THROW(store_->revoke_token("t_0000000000000000"), NotFound);

  const auto tokens = store_->list_tokens();
  ASSERT_EQ(tokens.size(), 2u);
  // Both were made in the same millisecond, so their order is by random id: find by id.
  const auto listed = std::find_if(tokens.begin(), tokens.end(),
                                   [&](const proto::TokenInfo& t) { return t.id == submitter.id; });
  ASSERT_NE(listed, tokens.end());
  EXPECT_EQ(listed->revoked_at_ms, clock_.now_ms());

  EXPECT_THROW(store_->add_token("x", spec(proto::Role::kViewer, "*")), Invalid);
  EXPECT_THROW(store_->add_token("y", spec(proto::Role::kSubmitter, "Bad Name")), Invalid);
  EXPECT_NO_THROW(store_->add_token("z", spec(proto::Role::kWorker, "*")));
}

TEST_P(ProjectTest, ObjectsBelongToProjectsAndListingsFilterThem) {
  const proto::Mission a = mission_in(*store_, "harbour", "pier-a");
  const proto::Mission b = mission_in(*store_, "dock", "pier-b");
  const proto::Mission c = make_mission("pier-c");  // no project named: default
  EXPECT_EQ(a.project, "harbour");
  EXPECT_EQ(c.project, "default");
  EXPECT_EQ(store_->get_mission(b.id).project, "dock");
  EXPECT_EQ(store_->list_missions("", "harbour").size(), 1u);
  EXPECT_EQ(store_->list_missions("pier", "*").size(), 3u);
  EXPECT_EQ(store_->list_missions("pier").size(), 3u);

  proto::JobRequest request = job_request(a);
  const proto::Job job = store_->create_job(request, "");
  EXPECT_EQ(job.project, "harbour");
  EXPECT_EQ(job.mission_name, "pier-a");
  request.project = "dock";  // a dock token naming a harbour mission: as if it did not exist
  EXPECT_THROW(store_->create_job(request, ""), NotFound);
  store_->create_job(job_request(b), "");

  JobFilter filter;
  filter.project = "harbour";
  auto jobs = store_->list_jobs(filter);
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].id, job.id);
  filter.project = "*";
  EXPECT_EQ(store_->list_jobs(filter).size(), 2u);
  filter.project = "";
  filter.mission_name = "r-b";  // substring of the mission's name
  jobs = store_->list_jobs(filter);
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].mission_name, "pier-b");

  // An artifact carries its job's project; an upload its own.
  const proto::Lease lease = this->lease();
  ASSERT_EQ(lease.job.id, job.id);  // oldest first
  EXPECT_EQ(lease.job.worker, "host:1");
  const std::string blob = store_->put_blob("map bytes");
  const proto::Artifact artifact =
      store_->add_artifact(job.id, {lease.lease_id, "ingest", "report.json", blob});
  EXPECT_EQ(store_->get_artifact(artifact.id).project, "harbour");
  proto::UploadRequest upload_request{"m.tar", 10, "dock"};
  EXPECT_EQ(store_->get_upload(store_->create_upload(upload_request).id).project, "dock");
  upload_request.project = "No Such";
  EXPECT_THROW(store_->create_upload(upload_request), Invalid);
}

TEST_P(ProjectTest, UsageCountsEachReferencedBlobOnceAndQuotasAreKept) {
  const std::string bytes = testing::random_bytes(1000, 15);
  proto::UploadRequest request{"a.bin", 1000, "alpha"};
  const proto::Upload upload = store_->create_upload(request);
  store_->append_upload(upload.id, 0, bytes.data(), bytes.size());
  const std::string sha256 = store_->complete_upload(upload.id, sha256_bytes(bytes));
  EXPECT_TRUE(store_->project_has_blob("alpha", sha256));
  EXPECT_FALSE(store_->project_has_blob("beta", sha256));
  EXPECT_EQ(store_->project_usage("alpha"), 1000);
  EXPECT_EQ(store_->project_usage("beta"), 0);
  // beta's mission naming the same bytes: beta holds it too; alpha's mission adds nothing.
  proto::MissionRequest mission;
  mission.name = "m";
  mission.bundle_blob = sha256;
  mission.project = "beta";
  store_->create_mission(mission);
  mission.project = "alpha";
  store_->create_mission(mission);
  EXPECT_TRUE(store_->project_has_blob("beta", sha256));
  EXPECT_EQ(store_->project_usage("alpha"), 1000);
  EXPECT_EQ(store_->project_usage("beta"), 1000);
  // An open upload counts with its announced size.
  store_->create_upload({"b.bin", 500, "alpha"});
  EXPECT_EQ(store_->project_usage("alpha"), 1500);
  EXPECT_EQ(store_->project_usage("nobody"), 0);

  EXPECT_EQ(store_->set_project_quota("alpha", 4096).quota_bytes, 4096);
  EXPECT_EQ(store_->set_project_quota("gamma", 10).name, "gamma");  // made when new
  int64_t alpha_quota = -1;
  for (const proto::Project& project : store_->list_projects())
    if (project.name == "alpha") alpha_quota = project.quota_bytes;
  EXPECT_EQ(alpha_quota, 4096);
  EXPECT_THROW(store_->set_project_quota("alpha", -1), Invalid);
  EXPECT_THROW(store_->set_project_quota("bad name!", 1), Invalid);
}

TEST_P(ProjectTest, LeaseTakesOnlyTheWorkersProject) {
  const proto::Mission a = mission_in(*store_, "harbour", "pier-a");
  const proto::Mission b = mission_in(*store_, "dock", "pier-b");
  const proto::Job job_a = store_->create_job(job_request(a), "");
  const proto::Job job_b = store_->create_job(job_request(b), "");
  proto::LeaseRequest request{"dock-worker", 30};
  request.project = "dock";
  auto lease = store_->lease_job(request);
  ASSERT_TRUE(lease);
  EXPECT_EQ(lease->job.id, job_b.id) << "the older harbour job is not the dock worker's";
  EXPECT_FALSE(store_->lease_job(request));
  request.project = "*";
  lease = store_->lease_job(request);
  ASSERT_TRUE(lease);
  EXPECT_EQ(lease->job.id, job_a.id);
}

TEST_P(ProjectTest, BatchIsMadeInOneTransactionAndCountedByState) {
  std::vector<proto::Mission> harbour;
  for (int i = 0; i < 5; ++i)
    harbour.push_back(mission_in(*store_, "harbour", "survey-" + std::to_string(i)));
  const proto::Mission other = mission_in(*store_, "dock", "survey-x");

  proto::ReprocessRequest request;
  request.project = "harbour";
  request.name_prefix = "survey-";
  request.stages = {"ingest"};
  const proto::Batch batch = store_->create_batch(request);
  EXPECT_EQ(batch.id.rfind("b_", 0), 0u);
  EXPECT_EQ(batch.jobs, 5);
  EXPECT_EQ(batch.project, "harbour");
  JobFilter filter;
  filter.batch_id = batch.id;
  auto jobs = store_->list_jobs(filter);
  ASSERT_EQ(jobs.size(), 5u);
  for (const auto& job : jobs) {
    EXPECT_EQ(job.batch_id, batch.id);
    EXPECT_EQ(job.project, "harbour");
    EXPECT_EQ(job.stages, std::vector<std::string>{"ingest"});
  }

  // Finish two: one succeeded after 4 s, one failed after 2 s.
  auto first = lease();
  clock_.advance_ms(4000);
  store_->finish_job(first.job.id, {first.lease_id, ""}, true);
  auto second = lease();
  clock_.advance_ms(2000);
  store_->finish_job(second.job.id, {second.lease_id, "broken"}, false);
  const proto::Batch now = store_->get_batch(batch.id);
  EXPECT_EQ(now.jobs_by_state.at("queued"), 3);
  EXPECT_EQ(now.jobs_by_state.at("succeeded"), 1);
  EXPECT_EQ(now.jobs_by_state.at("failed"), 1);
  EXPECT_EQ(now.jobs_by_state.at("running"), 0);
  EXPECT_EQ(now.finished_jobs_timed, 2);
  // first: leased at t0, finished at t0 + 4 s; second: leased at t0 + 4 s, failed at t0 + 6 s.
  EXPECT_DOUBLE_EQ(now.mean_job_seconds, (4.0 + 2.0) / 2);

  // An id of another project, anywhere in the list: nothing is made.
  proto::ReprocessRequest by_id;
  by_id.project = "harbour";
  by_id.mission_ids = {harbour[0].id, other.id};
  by_id.stages = {"ingest"};
  try {
    store_->create_batch(by_id);
    FAIL() << "expected NotFound";
  } catch (const NotFound& error) {
    EXPECT_NE(std::string(error.what()).find("mission_ids[1]"), std::string::npos) << error.what();
  }
  filter.batch_id = "";
  filter.project = "harbour";
  EXPECT_EQ(store_->list_jobs(filter).size(), 5u) << "the refused batch made no job";
  by_id.name_prefix = "survey-";
  EXPECT_THROW(store_->create_batch(by_id), Invalid);
  EXPECT_THROW(store_->get_batch("b_0000000000000000"), NotFound);
}

// `keel reprocess --compare`: each new job compares with the job it reprocesses, its mission's
// latest succeeded job that is not a comparison job; a mission without one is reprocessed
// without comparing.
TEST_P(ProjectTest, ReprocessWithCompareNamesTheJobEachNewJobReprocesses) {
  const proto::Mission done = mission_in(*store_, "harbour", "survey-1");
  const proto::Mission fresh = mission_in(*store_, "harbour", "survey-2");
  auto finish = [&](const proto::Mission& mission, const std::vector<std::string>& stages,
                    bool ok) {
    proto::JobRequest request = job_request(mission);
    request.project = "harbour";
    request.stages = stages;
    const proto::Job job = store_->create_job(request, "");
    proto::LeaseRequest lease_request{"w", 30};
    lease_request.project = "harbour";
    const auto lease = store_->lease_job(lease_request);
    EXPECT_TRUE(lease && lease->job.id == job.id);
    clock_.advance_ms(1000);
    store_->finish_job(job.id, {lease->lease_id, ok ? "" : "broken"}, ok);
    return job.id;
  };
  const std::string older = finish(done, {"ingest"}, true);
  const std::string latest = finish(done, {"ingest", "refine"}, true);
  finish(done, {"ingest"}, false);    // later, but failed
  finish(done, {"compare"}, true);    // later, but a comparison job
  finish(fresh, {"ingest"}, false);   // the other mission never succeeded

  proto::ReprocessRequest request;
  request.project = "harbour";
  request.name_prefix = "survey-";
  request.stages = {"ingest", "map"};
  request.options = {{"map", {{"voxel_m", 0.05}}}, {"compare", {{"sensors", {"combined"}}}}};
  request.compare = true;
  const proto::Batch batch = store_->create_batch(request);
  EXPECT_EQ(batch.jobs, 2);
  EXPECT_EQ(batch.compared, 1);
  JobFilter filter;
  filter.batch_id = batch.id;
  for (const proto::Job& job : store_->list_jobs(filter)) {
    if (job.mission_id == done.id) {
      EXPECT_EQ(job.stages, (std::vector<std::string>{"ingest", "map", "compare"}));
      EXPECT_EQ(job.options["compare"]["job_a"], latest) << "not " << older;
      EXPECT_EQ(job.options["compare"]["sensors"], nlohmann::json({"combined"}));
      EXPECT_FALSE(job.options["compare"].contains("job_b")) << "B is the job itself";
      EXPECT_EQ(job.options["map"]["voxel_m"], 0.05);
    } else {
      EXPECT_EQ(job.mission_id, fresh.id);
      EXPECT_EQ(job.stages, (std::vector<std::string>{"ingest", "map"}));
      EXPECT_FALSE(job.options.contains("compare") && job.options["compare"].contains("job_a"));
    }
  }
  // Without --compare nothing is added.
  request.compare = false;
  const proto::Batch plain = store_->create_batch(request);
  EXPECT_EQ(plain.compared, 0);
  filter.batch_id = plain.id;
  for (const proto::Job& job : store_->list_jobs(filter))
    EXPECT_EQ(job.stages, (std::vector<std::string>{"ingest", "map"}));
}

TEST_P(ProjectTest, ReleasedJobIsQueuedAtOnceAndNotCountedAsExpiry) {
  const proto::Job job = store_->create_job(job_request(make_mission()), "");
  for (int round = 1; round <= 4; ++round) {  // more releases than the 3-expiry limit
    const proto::Lease lease = this->lease("w" + std::to_string(round));
    EXPECT_EQ(lease.job.attempts, round);
    const proto::Job released = store_->release_job(job.id, lease.lease_id);
    EXPECT_EQ(released.state, proto::JobState::kQueued);
    EXPECT_THROW(store_->heartbeat(job.id, {lease.lease_id, "", 0.0, {}}), LeaseLost);
    EXPECT_THROW(store_->release_job(job.id, lease.lease_id), LeaseLost);
  }
  EXPECT_EQ(store_->get_job(job.id).state, proto::JobState::kQueued);
}

TEST_P(ProjectTest, ExpiredLeasesAreRequeuedByOneCall) {
  const proto::Job job = store_->create_job(job_request(make_mission()), "");
  lease("w", 30);
  EXPECT_EQ(store_->requeue_expired_leases(), 0);
  clock_.advance_ms(30'000);
  EXPECT_EQ(store_->requeue_expired_leases(), 1);
  EXPECT_EQ(store_->get_job(job.id).state, proto::JobState::kQueued);
  EXPECT_EQ(store_->requeue_expired_leases(), 0);
}

TEST_P(ProjectTest, ChangeFeedReportsCommittedChangesUntilUnsubscribed) {
  std::mutex mutex;
  std::vector<Change> seen;
  auto subscription = store_->subscribe([&](const Change& change) {
    std::lock_guard<std::mutex> lock(mutex);
    seen.push_back(change);
  });
  const proto::Mission mission = mission_in(*store_, "harbour", "pier");
  const proto::Job job = store_->create_job(job_request(mission), "");
  const proto::Lease lease = this->lease();
  store_->heartbeat(job.id, {lease.lease_id, "ingest", 0.5, {"a line"}});
  store_->finish_job(job.id, {lease.lease_id, ""}, true);
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto states = std::vector<proto::JobState>{};
    bool logged = false;
    for (const Change& change : seen) {
      EXPECT_EQ(change.job_id, job.id);
      EXPECT_EQ(change.project, "harbour");
      if (change.kind == Change::Kind::kJob) states.push_back(change.state);
      logged |= change.kind == Change::Kind::kLog;
    }
    EXPECT_TRUE(logged);
    ASSERT_GE(states.size(), 3u);
    EXPECT_EQ(states.front(), proto::JobState::kQueued);
    EXPECT_EQ(states[1], proto::JobState::kRunning);
    EXPECT_EQ(states.back(), proto::JobState::kSucceeded);
  }
  // A failed write publishes nothing.
  const size_t before = seen.size();
  EXPECT_THROW(store_->finish_job(job.id, {lease.lease_id, ""}, true), Conflict);
  EXPECT_EQ(seen.size(), before);
  subscription.reset();
  store_->create_job(job_request(mission), "");
  EXPECT_EQ(seen.size(), before);
}

TEST_P(ProjectTest, ListenerMayEndItsOwnSubscription) {
  std::unique_ptr<Subscription> subscription;
  int calls = 0;
  subscription = store_->subscribe([&](const Change&) {
    ++calls;
    subscription.reset();
  });
  store_->create_job(job_request(make_mission()), "");
  store_->create_job(job_request(make_mission("other")), "");
  EXPECT_EQ(calls, 1);
}

TEST_P(ProjectTest, QueueSummaryCountsStatesWorkersAndTheLastHour) {
  const proto::Mission mission = make_mission();
  for (int i = 0; i < 3; ++i) store_->create_job(job_request(mission), "");
  const proto::Lease busy = lease("busy");
  EXPECT_TRUE(store_->lease_job({"idle-soon", 30}));
  auto done = store_->get_job(busy.job.id);
  clock_.advance_ms(10'000);
  store_->finish_job(done.id, {busy.lease_id, ""}, true);
  clock_.advance_ms(50'001);  // "busy" was last heard 50 s ago; "idle-soon" 60.001 s ago
  proto::QueueSummary summary = store_->queue_summary();
  EXPECT_EQ(summary.jobs_by_state.at("queued"), 1);
  EXPECT_EQ(summary.jobs_by_state.at("running"), 1);
  EXPECT_EQ(summary.jobs_by_state.at("succeeded"), 1);
  EXPECT_EQ(summary.finished_last_hour, 1);
  EXPECT_DOUBLE_EQ(summary.mean_job_seconds_last_hour, 10.0);
  ASSERT_EQ(summary.workers.size(), 2u);
  EXPECT_EQ(summary.workers[0].id, "busy");
  EXPECT_TRUE(summary.workers[0].alive);
  EXPECT_EQ(summary.workers[0].job_id, "");
  EXPECT_FALSE(summary.workers[1].alive);
  EXPECT_EQ(summary.workers_alive, 1);
  clock_.advance_ms(3'600'000);
  summary = store_->queue_summary();
  EXPECT_EQ(summary.finished_last_hour, 0);
  EXPECT_TRUE(summary.workers.empty());
}

// A store made before projects existed (schema version 2) opens with its data in 'default'
// and its tokens as admin tokens of every project.
TEST(ProjectMigration, VersionTwoDataMovesIntoDefault) {
  testing::TempDir dir;
  const std::string token = "kt_old_token_0123456789";
  {
    Database db(dir.path() / "keel.db");
    std::vector<Migration> v2(sqlite_migrations().begin(), sqlite_migrations().begin() + 2);
    ASSERT_EQ(apply_migrations(db, v2), 2);
    const std::string sha(64, 'a');
    db.exec("INSERT INTO blobs VALUES ('" + sha + "', 3, 0)");
    db.exec(
        "INSERT INTO missions (id, name, bundle_blob, created_at_ms) VALUES "
        "('m_0000000000000001', 'old', '" +
        sha + "', 1)");
    db.exec(
        "INSERT INTO jobs (id, mission_id, state, stages, options, created_at_ms) VALUES "
        "('j_0000000000000001', 'm_0000000000000001', 'queued', '[\"ingest\"]', '{}', 2)");
    db.exec("INSERT INTO api_tokens VALUES ('" + sha256_bytes(token) + "', 'initial', 3)");
  }
  auto store = open_sqlite_store(dir.path());
  EXPECT_EQ(store->get_mission("m_0000000000000001").project, "default");
  const proto::Job job = store->get_job("j_0000000000000001");
  EXPECT_EQ(job.project, "default");
  EXPECT_EQ(job.batch_id, "");
  auto info = store->check_token(token);
  ASSERT_TRUE(info);
  EXPECT_EQ(info->role, proto::Role::kAdmin);
  EXPECT_TRUE(info->all_projects());
  EXPECT_EQ(info->id, "t_" + sha256_bytes(token).substr(0, 16));
}

KEEL_STORE_TEST_SUITE(ProjectTest);

}  // namespace
}  // namespace keel::storage
