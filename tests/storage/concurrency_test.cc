// Several threads using one store at once, as the server's request threads do.
#include <gtest/gtest.h>

#include <atomic>
#include <set>
#include <thread>

#include "core/sha256.h"
#include "store_fixture.h"

namespace keel::storage {
namespace {

using testing::StoreTest;
using ConcurrencyTest = StoreTest;

TEST_P(ConcurrencyTest, CreateLeaseHeartbeatReadFromManyThreads) {
  const proto::Mission mission = make_mission();
  constexpr int kThreads = 4;
  constexpr int kJobsPerThread = 25;
  std::atomic<int> errors{0};
  std::vector<std::thread> threads;
  std::vector<std::vector<std::string>> created(kThreads);
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      try {
        for (int i = 0; i < kJobsPerThread; ++i) {
          const std::string key = "k-" + std::to_string(t) + "-" + std::to_string(i % 20);
          created[t].push_back(store_->create_job(job_request(mission), key).id);
          auto lease = store_->lease_job({"w" + std::to_string(t), 60});
          if (lease) {
            store_->heartbeat(lease->job.id, {lease->lease_id, "ingest", 0.5, {"line"}});
            store_->complete_stage(lease->job.id, "ingest", {lease->lease_id, {}, 1.0});
          }
          store_->get_job(created[t].back());
          store_->list_jobs({});
          store_->metrics();
        }
      } catch (const std::exception& error) {
        ADD_FAILURE() << "thread " << t << ": " << error.what();
        ++errors;
      }
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(errors.load(), 0);
  // Keys repeat after 20 per thread: 20 distinct jobs per thread, the repeats returned them.
  std::set<std::string> distinct;
  for (const auto& ids : created) distinct.insert(ids.begin(), ids.end());
  EXPECT_EQ(distinct.size(), static_cast<size_t>(kThreads * 20));
  const Metrics metrics = store_->metrics();
  EXPECT_EQ(metrics.jobs_by_state[static_cast<int>(proto::JobState::kRunning)] +
                metrics.jobs_by_state[static_cast<int>(proto::JobState::kQueued)],
            kThreads * 20);
  // Every leased job saw exactly one heartbeat line (a job is never leased twice at once).
  for (const proto::Job& job : store_->list_jobs({proto::JobState::kRunning, ""})) {
    EXPECT_EQ(job.attempts, 1) << job.id;
    EXPECT_EQ(store_->read_log(job.id, 0, 10).lines.size(), 1u) << job.id;
  }
}

TEST_P(ConcurrencyTest, ParallelUploadsAndBlobs) {
  constexpr int kThreads = 4;
  std::atomic<int> errors{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      try {
        // Two threads upload the same content: still one blob.
        const std::string bytes = testing::random_bytes(40'000, static_cast<unsigned>(t % 2));
        const proto::Upload upload = store_->create_upload({"f", 40'000});
        for (int64_t at = 0; at < 40'000; at += 8'000)
          store_->append_upload(upload.id, at, bytes.data() + at, 8'000);
        EXPECT_EQ(store_->complete_upload(upload.id, sha256_bytes(bytes)), sha256_bytes(bytes));
        store_->put_blob("small " + std::to_string(t % 2));
      } catch (const std::exception& error) {
        ADD_FAILURE() << "thread " << t << ": " << error.what();
        ++errors;
      }
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(errors.load(), 0);
  EXPECT_EQ(store_->metrics().blobs, 4);  // 2 uploaded contents + 2 small blobs
  EXPECT_EQ(store_->metrics().uploads_open, 0);
}

// 8 workers lease from 2,000 queued jobs at once (the concurrency test): every job
// is leased exactly once and none is lost; a stale lease's completion is rejected.
TEST_P(ConcurrencyTest, EightWorkersLeaseTwoThousandJobsEachExactlyOnce) {
  constexpr int kJobs = 2000;
  constexpr int kThreads = 8;
  const proto::Mission mission = make_mission();
  std::set<std::string> queued;
  for (int i = 0; i < kJobs; ++i)
    queued.insert(store_->create_job(job_request(mission, {"ingest"}), "").id);
  ASSERT_EQ(queued.size(), static_cast<size_t>(kJobs));

  std::vector<std::vector<proto::Lease>> leased(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      try {
        while (auto lease = store_->lease_job({"w" + std::to_string(t), 60})) {
          store_->finish_job(lease->job.id, {lease->lease_id, ""}, true);
          leased[t].push_back(std::move(*lease));
        }
      } catch (const std::exception& error) {
        ADD_FAILURE() << "worker " << t << ": " << error.what();
      }
    });
  for (auto& thread : threads) thread.join();

  std::multiset<std::string> taken;
  for (const auto& leases : leased)
    for (const auto& lease : leases) taken.insert(lease.job.id);
  EXPECT_EQ(taken.size(), static_cast<size_t>(kJobs)) << "every job leased once, none twice";
  EXPECT_EQ(std::set<std::string>(taken.begin(), taken.end()), queued) << "none lost";
  size_t busy_workers = 0;
  for (const auto& leases : leased) busy_workers += leases.empty() ? 0 : 1;
  EXPECT_GT(busy_workers, 1u) << "the workers ran side by side";
  const Metrics metrics = store_->metrics();
  EXPECT_EQ(metrics.jobs_by_state[static_cast<int>(proto::JobState::kSucceeded)], kJobs);
  EXPECT_EQ(metrics.jobs_by_state[static_cast<int>(proto::JobState::kQueued)], 0);

  // A stale lease: the job's lease expired and another worker holds it now.
  const proto::Job job = store_->create_job(job_request(mission, {"ingest"}), "");
  const proto::Lease stale = lease("slow", 30);
  clock_.advance_ms(31'000);
  const proto::Lease current = lease("fast", 30);
  EXPECT_EQ(current.job.id, job.id);
  EXPECT_THROW(store_->finish_job(job.id, {stale.lease_id, ""}, true), LeaseLost);
  EXPECT_THROW(store_->complete_stage(job.id, "ingest", {stale.lease_id, {}, 1.0}), LeaseLost);
  EXPECT_EQ(store_->get_job(job.id).state, proto::JobState::kRunning);
  EXPECT_EQ(store_->finish_job(job.id, {current.lease_id, ""}, true).state,
            proto::JobState::kSucceeded);
}

KEEL_STORE_TEST_SUITE(ConcurrencyTest);

}  // namespace
}  // namespace keel::storage
