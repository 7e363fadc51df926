// keel jobs --batch: the ETA against its closed form, and the printed counts.
#include "client/batch_progress.h"

#include <gtest/gtest.h>

namespace keel::client {
namespace {

proto::Batch batch_with(int64_t queued, int64_t running, int64_t succeeded, int64_t failed,
                        double mean_s, int64_t timed) {
  proto::Batch batch;
  batch.id = "b_0000000000000001";
  batch.project = "default";
  batch.jobs = queued + running + succeeded + failed;
  batch.jobs_by_state = {{"queued", queued},
                         {"running", running},
                         {"succeeded", succeeded},
                         {"failed", failed},
                         {"canceled", 0}};
  batch.mean_job_seconds = mean_s;
  batch.finished_jobs_timed = timed;
  return batch;
}

TEST(BatchProgress, EtaIsMeanTimesRemainingWorkOverParallelism) {
  // 10 queued + 4 running (half done) at 4 at once, 60 s a job: 60 * (10 + 2) / 4 = 180 s.
  const auto eta = batch_eta_seconds(batch_with(10, 4, 6, 0, 60.0, 6));
  ASSERT_TRUE(eta.has_value());
  EXPECT_DOUBLE_EQ(*eta, 180.0);
  // The same as work left (queued whole, running half) spread over the 4 running slots.
  double work_left_s = 10 * 60.0;
  for (int slot = 0; slot < 4; ++slot) work_left_s += 30.0;
  EXPECT_DOUBLE_EQ(work_left_s / 4, *eta);
}

TEST(BatchProgress, NoEtaWithoutAMeanOrWithoutRunningJobs) {
  EXPECT_FALSE(batch_eta_seconds(batch_with(5, 2, 0, 0, 0.0, 0)).has_value());
  EXPECT_FALSE(batch_eta_seconds(batch_with(5, 0, 3, 0, 10.0, 3)).has_value());
  EXPECT_EQ(batch_eta_seconds(batch_with(0, 0, 3, 1, 10.0, 4)), 0.0);
}

TEST(BatchProgress, StatusNamesEveryStateAndTheEta) {
  const std::string text = format_batch_status(batch_with(10, 4, 6, 1, 60.0, 7));
  EXPECT_NE(text.find("21 jobs, 10 queued, 4 running, 6 succeeded, 1 failed, 0 canceled"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("ETA 3m 00s"), std::string::npos) << text;
  EXPECT_NE(format_batch_status(batch_with(0, 0, 3, 0, 1.0, 3)).find("finished"),
            std::string::npos);
  EXPECT_NE(format_batch_status(batch_with(3, 1, 0, 0, 0.0, 0)).find("no ETA"), std::string::npos);
}

TEST(BatchProgress, DurationsReadAsHoursMinutesSeconds) {
  EXPECT_EQ(format_duration_s(12.4), "12s");
  EXPECT_EQ(format_duration_s(245), "4m 05s");
  EXPECT_EQ(format_duration_s(3720), "1h 02m");
  EXPECT_EQ(format_duration_s(-3), "0s");
}

}  // namespace
}  // namespace keel::client
