// End-to-end: real keel-server, keel-worker, keel and keel-sim processes on loopback.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <fstream>
#include <random>
#include <regex>
#include <thread>

#include "core/sha256.h"
#include "tests/e2e/cluster.h"

namespace keel::e2e {
namespace {

namespace fs = std::filesystem;
using proto::Job;
using proto::JobState;

// One short simulated mission shared by the tests (keel-sim is deterministic per seed).
class EndToEnd : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    missions_ = new TempDir();
    simulate_mission(small_mission(), 10, "imu,dvl,lidar_h,sonar,depth");
    // Big enough that a job is still running when a test kills its worker or server.
    simulate_mission(big_mission(), 90, "imu,dvl,lidar_h,lidar_v,sonar");
  }
  static void TearDownTestSuite() { delete missions_; }
  static fs::path small_mission() { return missions_->path() / "small"; }
  static fs::path big_mission() { return missions_->path() / "big"; }

  // Submits with the CLI and returns the job id it printed.
  static std::string submit(const Cluster& cluster, const fs::path& mission) {
    const RunResult r = cluster.keel({"submit", mission.string(), "--stages", "ingest", "-q"});
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::smatch match;
    const std::regex job_id("j_[0-9a-f]+");
    if (!std::regex_search(r.output, match, job_id)) ADD_FAILURE() << "no job id in: " << r.output;
    return match.str();
  }

  TempDir root_;

 private:
  static TempDir* missions_;
};
TempDir* EndToEnd::missions_ = nullptr;

bool terminal(const Job& job) { return proto::is_terminal(job.state); }

// The "done when": submit with keel, wait for success, fetch every artifact and
// check their SHA-256 against the server's list.
TEST_F(EndToEnd, SubmitWaitFetchEveryArtifactWithMatchingSha256) {
  Cluster cluster(root_.path(), /*workers=*/1);
  const RunResult submitted =
      cluster.keel({"submit", small_mission().string(), "--stages", "ingest", "--wait", "-q"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  const std::string job_id = std::regex_replace(submitted.output, std::regex("(.|\\n)*?(j_[0-9a-f]+)(.|\\n)*"), "$2");

  auto api = cluster.api();
  const Job job = api.get_job(job_id);
  EXPECT_EQ(job.state, JobState::kSucceeded) << job.error;
  const auto artifacts = api.list_artifacts(job_id);
  ASSERT_FALSE(artifacts.empty());

  const fs::path out = root_.path() / "fetched";
  const RunResult fetched = cluster.keel({"fetch", job_id, "-o", out.string(), "-q"});
  ASSERT_EQ(fetched.exit_code, 0) << fetched.output;
  for (const auto& artifact : artifacts) {
    ASSERT_TRUE(fs::exists(out / artifact.name)) << artifact.name;
    EXPECT_EQ(static_cast<int64_t>(fs::file_size(out / artifact.name)), artifact.size);
    EXPECT_EQ(keel::sha256_file(out / artifact.name), artifact.sha256) << artifact.name;
  }

  // The report counts what keel-sim wrote: 10 s of IMU at 200 Hz and DVL at 20 Hz, both ends included.
  std::ifstream in(out / "report.json");
  const auto report = nlohmann::json::parse(in);
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["imu"]["count"].get<int>(), 2001);
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["dvl"]["count"].get<int>(), 201);
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["lidar_h"]["count"].get<int>(), 100);
}

// A stage that throws fails its job with that message; other jobs and the server go on.
TEST_F(EndToEnd, BadMissionFailsItsJobWithTheReasonAndTheServerGoesOn) {
  Cluster cluster(root_.path(), /*workers=*/1);
  const fs::path broken = root_.path() / "broken";
  fs::copy(small_mission(), broken, fs::copy_options::recursive);
  {  // Duplicate the timestamp of data row 5 into row 6 (file lines 6 and 7).
    std::ifstream in(broken / "imu.csv");
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    lines[6] = lines[5];
    std::ofstream out(broken / "imu.csv", std::ios::trunc);
    for (const auto& line : lines) out << line << '\n';
  }
  const RunResult failed = cluster.keel({"submit", broken.string(), "--stages", "ingest", "--wait", "-q"});
  EXPECT_EQ(failed.exit_code, 4) << failed.output;  // 4 = the watched job failed
  auto api = cluster.api();
  const auto jobs = api.list_jobs("failed");
  ASSERT_EQ(jobs.size(), 1u);
  // Named as in the user's bundle, not by the worker's copy in its cache (issue 18).
  EXPECT_EQ(jobs[0].error.rfind("ingest: imu.csv:7: ", 0), 0u) << jobs[0].error;
  EXPECT_EQ(jobs[0].error.find("/jobs/"), std::string::npos) << jobs[0].error;

  const RunResult good = cluster.keel({"submit", small_mission().string(), "--stages", "ingest", "--wait", "-q"});
  EXPECT_EQ(good.exit_code, 0) << good.output;
  EXPECT_EQ(api.list_jobs("succeeded").size(), 1u);
  EXPECT_EQ(api.list_jobs("failed").size(), 1u);
}

// A worker killed mid-job: its lease expires and another worker finishes the job.
TEST_F(EndToEnd, WorkerKilledMidJobIsReplacedAfterItsLeaseExpires) {
  const fs::path big = big_mission();
  Cluster cluster(root_.path(), /*workers=*/0);
  const std::string job_id = submit(cluster, big);
  auto api = cluster.api();

  Process& first = cluster.start_worker(/*lease_seconds=*/2);
  Job job = wait_job(api, job_id, [](const Job& j) { return j.state != JobState::kQueued; }, 60);
  ASSERT_EQ(job.state, JobState::kRunning) << "the job ended before the worker could be killed";
  first.signal(SIGKILL);
  first.wait_for(std::chrono::seconds(5));

  cluster.start_worker(/*lease_seconds=*/30);
  job = wait_job(api, job_id, terminal, 240);
  EXPECT_EQ(job.state, JobState::kSucceeded) << job.error;
  EXPECT_EQ(job.attempts, 2);
}

// SIGKILL of the server in the middle of an upload: after a restart the upload resumes
// from the committed offset and completes with the right SHA-256; nothing half-written.
TEST_F(EndToEnd, ServerKilledDuringUploadResumesAfterRestart) {
  const fs::path file = root_.path() / "payload.bin";
  {
    std::mt19937_64 rng(7);
    std::ofstream out(file, std::ios::binary);
    for (int i = 0; i < (48 << 20) / 8; ++i) {
      const uint64_t word = rng();
      out.write(reinterpret_cast<const char*>(&word), sizeof(word));
    }
  }
  const std::string expected_sha = keel::sha256_file(file);
  Cluster cluster(root_.path(), /*workers=*/0, free_port());

  client::ClientConfig config;
  config.url = cluster.url();
  config.token = cluster.token();
  config.chunk_bytes = 4 << 20;
  config.retries = 1;
  config.retry_backoff_s = 0.05;
  {
    client::ApiClient api(config);
    EXPECT_ANY_THROW(api.upload_file(file, root_.path() / "state", [&](int64_t done, int64_t) {
      if (done >= (20 << 20)) cluster.kill_server();
    }));
  }
  cluster.start_server();
  client::ApiClient api(config);
  const std::string blob = api.upload_file(file, root_.path() / "state");
  EXPECT_EQ(blob, expected_sha);
  EXPECT_LT(api.stats().upload_body_bytes, 48 << 20) << "the upload restarted from zero";
  EXPECT_GE(api.stats().upload_body_bytes, 1) << "nothing was resent";

  // Every stored blob is whole: its name is its content's SHA-256.
  int blobs = 0;
  for (const auto& entry : fs::recursive_directory_iterator(cluster.data_dir() / "blobs")) {
    if (!entry.is_regular_file()) continue;
    ++blobs;
    EXPECT_EQ(keel::sha256_file(entry.path()), entry.path().filename().string());
  }
  EXPECT_EQ(blobs, 1);
}

// SIGKILL of the server while a job runs: after a restart the job runs again to success.
TEST_F(EndToEnd, ServerKilledDuringRunningJobRunsAgainAfterRestart) {
  const fs::path big = big_mission();
  Cluster cluster(root_.path(), /*workers=*/0, free_port());
  const std::string job_id = submit(cluster, big);
  cluster.start_worker(/*lease_seconds=*/2);
  {
    auto api = cluster.api();
    const Job job = wait_job(api, job_id, [](const Job& j) { return j.state != JobState::kQueued; }, 60);
    ASSERT_EQ(job.state, JobState::kRunning);
  }
  cluster.kill_server();
  std::this_thread::sleep_for(std::chrono::seconds(3));  // longer than the lease
  cluster.start_server();
  auto api = cluster.api();
  const Job job = wait_job(api, job_id, terminal, 240);
  EXPECT_EQ(job.state, JobState::kSucceeded) << job.error;
  for (const auto& artifact : api.list_artifacts(job_id)) {
    const fs::path copy = root_.path() / ("check-" + artifact.name);
    api.download("/v1/artifacts/" + artifact.id, copy, artifact.sha256);
    EXPECT_EQ(keel::sha256_file(copy), artifact.sha256);
  }
}

// The pids of keel-worker processes whose command line names this data folder's token.
std::vector<int> workers_of(const fs::path& data_dir) {
  std::vector<int> pids;
  const std::string token_file = (data_dir / "worker-token").string();
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = read_file(entry.path() / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.find("keel-worker") != std::string::npos && cmdline.find(token_file) != std::string::npos)
      pids.push_back(std::stoi(name));
  }
  return pids;
}

// Local workers die with their server, even a SIGKILLed one: no orphans lease jobs later.
TEST_F(EndToEnd, LocalWorkersDoNotOutliveAKilledServer) {
  Cluster cluster(root_.path(), /*workers=*/2);
  for (int i = 0; i < 100 && workers_of(cluster.data_dir()).size() < 2; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_EQ(workers_of(cluster.data_dir()).size(), 2u);
  cluster.kill_server();
  for (int i = 0; i < 100 && !workers_of(cluster.data_dir()).empty(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  for (int pid : workers_of(cluster.data_dir()))
    ADD_FAILURE() << "worker " << pid << " outlived its server: "
                  << read_file("/proc/" + std::to_string(pid) + "/status").substr(0, 120);
}

}  // namespace
}  // namespace keel::e2e
