// `keel-worker serve` against a real keel-server on loopback (no local workers): a job
// succeeds and its report.json is an artifact; a stage error fails the job with the stage's
// message and the worker leases the next job; a cancel stops the stage; SIGTERM gives the
// lease back so another worker resumes the job at once; --exit-when-idle ends an idle worker.
#include <gtest/gtest.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "client/api_client.h"
#include "tests/child_process.h"
#include "tests/temp_dir.h"
#include "tests/worker/pipeline/test_missions.h"

namespace keel {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::Child;

using keel::testing::read_file;

class LeaseLoopTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("keel_lease_loop_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    server_ = std::make_unique<Child>(
        KEEL_SERVER_BIN,
        std::vector<std::string>{"--data-dir", (dir_ / "data").string(), "--listen", "127.0.0.1:0",
                                 "--workers", "0"},
        dir_ / "server.out", dir_ / "server.err");
    const fs::path url_file = dir_ / "data" / "server.url";
    for (int i = 0; i < 600 && !fs::exists(url_file); ++i) std::this_thread::sleep_for(50ms);
    ASSERT_TRUE(fs::exists(url_file)) << read_file(dir_ / "server.err");
    url_ = read_file(url_file);
    while (!url_.empty() && std::isspace(static_cast<unsigned char>(url_.back()))) url_.pop_back();
    client::ClientConfig config;
    config.url = url_;
    std::string token = read_file(dir_ / "data" / "token");
    config.token = token.substr(0, token.find_first_of(" \r\n"));
    api_ = std::make_unique<client::ApiClient>(config);
  }
  void TearDown() override {
    api_.reset();
    if (server_) {
      server_->signal(SIGTERM);
      server_->wait(20s);
      server_.reset();
    }
    fs::remove_all(dir_);
  }

  // Uploads `mission_dir` as a tar and queues a job running `stages` on it.
  proto::Job submit(const fs::path& mission_dir, std::vector<std::string> stages = {"ingest"}) {
    const fs::path tar = dir_ / ("bundle" + std::to_string(submitted_++) + ".tar");
    const std::string command = "tar -C " + mission_dir.string() + " -cf " + tar.string() + " .";
    EXPECT_EQ(std::system(command.c_str()), 0);
    proto::MissionRequest mission;
    mission.name = "m" + std::to_string(submitted_);
    mission.bundle_blob = api_->upload_file(tar, dir_ / "client-state");
    const proto::Mission stored = api_->create_mission(mission);
    proto::JobRequest request;
    request.mission_id = stored.id;
    request.stages = std::move(stages);
    return api_->create_job(request);
  }

  std::unique_ptr<Child> start_worker(const std::string& name,
                                      std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"serve",
                                     "--server",
                                     url_,
                                     "--token-file",
                                     (dir_ / "data" / "token").string(),
                                     "--cache-dir",
                                     (dir_ / "cache").string(),
                                     "--poll-seconds",
                                     "0.1",
                                     "--name",
                                     name};
    args.insert(args.end(), extra.begin(), extra.end());
    return std::make_unique<Child>(KEEL_WORKER_BIN, args, dir_ / (name + ".out"),
                                   dir_ / (name + ".err"));
  }
  std::string worker_log(const std::string& name) const {
    return read_file(dir_ / (name + ".out")) + read_file(dir_ / (name + ".err"));
  }

  // Polls the job until `done` holds (or 120 s pass).
  proto::Job wait_job(const std::string& id, const std::function<bool(const proto::Job&)>& done) {
    proto::Job job;
    for (int i = 0; i < 2400; ++i) {
      job = api_->get_job(id);
      if (done(job) || proto::is_terminal(job.state)) break;
      std::this_thread::sleep_for(50ms);
    }
    return job;
  }
  static bool finished(const proto::Job& job) { return proto::is_terminal(job.state); }

  // A job long enough to be still running when the test sees it (idle machines are fast),
  // leased by a new worker for far longer than the test: only a release queues it again.
  // Returns the job as seen running (or as it ended).
  proto::Job run_long_job(const std::string& worker_name, std::unique_ptr<Child>* worker) {
    testing::write_long_mission(dir_ / "long", 200000);
    const proto::Job job = submit(dir_ / "long");
    *worker = start_worker(worker_name, {"--lease-seconds", "600"});
    return wait_job(job.id, [](const proto::Job& j) {
      return j.state == proto::JobState::kRunning && j.stage == "ingest" && j.progress > 0.0;
    });
  }

  fs::path dir_;
  std::string url_;
  std::unique_ptr<Child> server_;
  std::unique_ptr<client::ApiClient> api_;
  int submitted_ = 0;
};

TEST_F(LeaseLoopTest, JobSucceedsWithReportArtifact) {
  testing::write_tiny_mission(dir_ / "tiny");
  const proto::Job job = submit(dir_ / "tiny");
  auto worker = start_worker("w1", {"--once"});
  ASSERT_EQ(worker->wait(120s), 0) << worker_log("w1");

  const proto::Job done = api_->get_job(job.id);
  EXPECT_EQ(done.state, proto::JobState::kSucceeded) << done.error;
  EXPECT_EQ(done.completed_stages, std::vector<std::string>{"ingest"});
  const auto artifacts = api_->list_artifacts(job.id);
  ASSERT_EQ(artifacts.size(), 2u);
  EXPECT_EQ(artifacts[0].name, "report.json");
  EXPECT_EQ(artifacts[1].name, "report.html");
  for (const auto& artifact : artifacts) {
    EXPECT_EQ(artifact.stage, "ingest");
    api_->download("/v1/artifacts/" + artifact.id, dir_ / artifact.name, artifact.sha256);
  }
  const auto report = nlohmann::json::parse(read_file(dir_ / "report.json"));
  EXPECT_EQ(report["keel_report"], 1);
  EXPECT_EQ(report["job"]["id"], job.id);
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["imu"]["count"], 6);
  EXPECT_NE(read_file(dir_ / "report.html").find(job.id), std::string::npos);

  // The job log carries the worker's lines, delivered by heartbeats.
  std::string log;
  for (const auto& line : api_->read_log(job.id, 0).lines) log += line.text + "\n";
  EXPECT_NE(log.find("ingest: started"), std::string::npos) << log;
  // The per-process work folder is gone; the bundle stays cached by its SHA-256.
  for (const auto& item : fs::directory_iterator(dir_ / "cache"))
    EXPECT_EQ(item.path().filename(), "blobs") << item.path();
}

TEST_F(LeaseLoopTest, StageErrorFailsTheJobAndTheWorkerTakesTheNext) {
  testing::write_tiny_mission(dir_ / "broken");
  fs::remove(dir_ / "broken" / "imu.csv");
  testing::write_tiny_mission(dir_ / "tiny");
  const proto::Job broken = submit(dir_ / "broken");
  auto worker = start_worker("w1");
  const proto::Job failed = wait_job(broken.id, finished);
  EXPECT_EQ(failed.state, proto::JobState::kFailed);
  // The user's names (mission.yaml, imu.csv), not the worker's cache paths (issue 18).
  EXPECT_EQ(failed.error, "ingest: mission.yaml: sensors[0].file: 'imu.csv' not found")
      << failed.error;
  // The failed job's report names the stage and the error.
  const auto artifacts = api_->list_artifacts(broken.id);
  ASSERT_EQ(artifacts.size(), 2u);
  EXPECT_EQ(artifacts[0].name, "report.json");
  api_->download("/v1/artifacts/" + artifacts[0].id, dir_ / "failed.json", artifacts[0].sha256);
  const auto report = nlohmann::json::parse(read_file(dir_ / "failed.json"));
  EXPECT_EQ(report["failed"]["stage"], "ingest");
  EXPECT_EQ(report["failed"]["error"], failed.error);

  const proto::Job good = submit(dir_ / "tiny");
  EXPECT_EQ(wait_job(good.id, finished).state, proto::JobState::kSucceeded) << worker_log("w1");
  worker->signal(SIGTERM);
  EXPECT_EQ(worker->wait(30s), 0) << worker_log("w1");
}

TEST_F(LeaseLoopTest, CancelStopsTheRunningStage) {
  testing::write_long_mission(dir_ / "long", 200000);
  const proto::Job job = submit(dir_ / "long");
  auto worker = start_worker("w1", {"--once"});
  const proto::Job running = wait_job(job.id, [](const proto::Job& j) {
    return j.state == proto::JobState::kRunning && j.stage == "ingest" && j.progress > 0.0;
  });
  ASSERT_EQ(running.state, proto::JobState::kRunning);
  const auto canceled_at = std::chrono::steady_clock::now();
  api_->cancel_job(job.id);

  // With --once the worker exits after the job: it stopped the stage instead of finishing it.
  EXPECT_EQ(worker->wait(60s), 0) << worker_log("w1");
  std::cout << "worker exited "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - canceled_at).count()
            << " s after the cancel\n";
  EXPECT_NE(worker_log("w1").find("canceled by the server"), std::string::npos) << worker_log("w1");
  const proto::Job after = api_->get_job(job.id);
  EXPECT_EQ(after.state, proto::JobState::kCanceled);
  EXPECT_TRUE(after.completed_stages.empty());
  EXPECT_TRUE(api_->list_artifacts(job.id).empty());
}

TEST_F(LeaseLoopTest, SigtermGivesTheLeaseBackAndAnotherWorkerResumesItAtOnce) {
  std::unique_ptr<Child> first;
  const proto::Job job = run_long_job("w1", &first);
  ASSERT_EQ(job.state, proto::JobState::kRunning);
  // Twice, as `scancel --signal=TERM --full` delivers it (to the worker, and through the
  // batch shell that forwards it): the same graceful stop, not an "exit now".
  first->signal(SIGTERM);
  std::this_thread::sleep_for(50ms);
  first->signal(SIGTERM);
  EXPECT_EQ(first->wait(30s), 0) << worker_log("w1");
  EXPECT_NE(worker_log("w1").find("lease given back"), std::string::npos) << worker_log("w1");
  const proto::Job released = api_->get_job(job.id);
  EXPECT_EQ(released.state, proto::JobState::kQueued) << "queued at once, not after 600 s";

  auto second = start_worker("w2", {"--once"});
  // The whole long mission again: minutes on a loaded 2-core machine, seconds on an idle one.
  EXPECT_EQ(second->wait(480s), 0) << worker_log("w2");
  const proto::Job done = api_->get_job(job.id);
  EXPECT_EQ(done.state, proto::JobState::kSucceeded) << done.error;
  EXPECT_EQ(done.attempts, 2);
}

TEST_F(LeaseLoopTest, AStopWhileTheServerIsDownGivesTheLeaseBackWhenItReturns) {
  // keel-server killed: its local workers stop (PR_SET_PDEATHSIG) while nobody answers. The
  // worker asks again until the server is back, so the job is queued by its release, not by
  // its lease expiring (which would count toward "lease expired 3 times").
  std::unique_ptr<Child> worker;
  const proto::Job job = run_long_job("w1", &worker);
  ASSERT_EQ(job.state, proto::JobState::kRunning);
  server_->signal(SIGKILL);
  server_->wait(20s);
  worker->signal(SIGTERM);
  std::this_thread::sleep_for(3s);  // the worker meets only refused connections meanwhile
  EXPECT_EQ(worker->wait(0ms), -1)
      << "gave up while the lease had 600 s left: " << worker_log("w1");
  const std::string listen = url_.substr(url_.find("://") + 3);
  server_ = std::make_unique<Child>(KEEL_SERVER_BIN,
                                    std::vector<std::string>{"--data-dir", (dir_ / "data").string(),
                                                             "--listen", listen, "--workers", "0"},
                                    dir_ / "server2.out", dir_ / "server2.err");
  EXPECT_EQ(worker->wait(60s), 0) << worker_log("w1");
  EXPECT_NE(worker_log("w1").find("lease given back"), std::string::npos) << worker_log("w1");
  const proto::Job released = api_->get_job(job.id);
  EXPECT_EQ(released.state, proto::JobState::kQueued) << "queued by the release, not in 600 s";
  EXPECT_EQ(released.error, "");
}

TEST_F(LeaseLoopTest, ExitWhenIdleEndsTheWorkerAfterItsLastJob) {
  testing::write_tiny_mission(dir_ / "tiny");
  const proto::Job job = submit(dir_ / "tiny");
  const auto start = std::chrono::steady_clock::now();
  auto worker = start_worker("w1", {"--exit-when-idle", "2", "--wait-seconds", "1"});
  EXPECT_EQ(worker->wait(120s), 0) << worker_log("w1");
  EXPECT_GE(std::chrono::steady_clock::now() - start, 2s) << "idle for 2 s before leaving";
  EXPECT_EQ(api_->get_job(job.id).state, proto::JobState::kSucceeded) << worker_log("w1");
  EXPECT_NE(worker_log("w1").find("--exit-when-idle"), std::string::npos) << worker_log("w1");
}

}  // namespace
}  // namespace keel
