// The client and the `keel` CLI against a real keel-server (started with --workers 0):
// upload resume after a drop, download resume from a .part, SHA-256 check, the typed
// client and worker calls, and the CLI's idempotent submit and exit codes.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <memory>
#include <random>
#include <thread>

#include "client/api_client.h"
#include "client/submit.h"
#include "server_process.h"
#include "core/sha256.h"
#include "tests/temp_dir.h"

namespace keel::client {
namespace {

namespace fs = std::filesystem;
using keel::testing::read_file;
using testing::ServerProcess;
using keel::testing::TempDir;
using keel::testing::write_file;

#ifdef KEEL_SERVER_BINARY
constexpr const char* kServerBinary = KEEL_SERVER_BINARY;
#else
constexpr const char* kServerBinary = "";
#endif
#ifdef KEEL_CLI_BINARY
constexpr const char* kCliBinary = KEEL_CLI_BINARY;
#else
constexpr const char* kCliBinary = "";
#endif

struct SimulatedDrop {};

std::string random_bytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::string out(n, '\0');
  for (auto& c : out) c = static_cast<char>(rng() & 0xff);
  return out;
}

class ServerIntegration : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::string(kServerBinary).empty() || !fs::exists(kServerBinary))
      GTEST_SKIP() << "keel-server not built (" << kServerBinary << ")";
    server_ = std::make_unique<ServerProcess>(kServerBinary, dir_.path() / "data");
  }

  ClientConfig config(int64_t chunk_bytes = 1 << 20) const {
    ClientConfig c;
    c.url = server_->url();
    c.token = server_->token();
    c.chunk_bytes = chunk_bytes;
    c.timeout_s = 20;
    return c;
  }

  // A minimal mission folder the server accepts (a tar holding mission.yaml).
  fs::path make_mission(const std::string& name) {
    const fs::path root = dir_.path() / name;
    write_file(root / "mission.yaml",
               "keel_mission: 1\nname: " + name +
                   "\nplatform: usv\nsensors:\n  - name: imu\n    type: imu\n"
                   "    file: imu.csv\n    rate_hz: 200\n");
    write_file(root / "imu.csv", "t,wx,wy,wz,ax,ay,az\n0.0,0,0,0,0,0,9.81\n");
    return root;
  }

  TempDir dir_;
  std::unique_ptr<ServerProcess> server_;
};

TEST_F(ServerIntegration, UploadResumesAtTheServersOffsetAfterADrop) {
  const int64_t chunk = 64 << 10;
  const std::string bytes = random_bytes(16 * chunk + 123, 1);  // 17 chunks
  write_file(dir_.path() / "big.bin", bytes);
  const fs::path state = dir_.path() / "state";

  // First run: the link "drops" after 8 chunks were committed.
  {
    ApiClient client(config(chunk));
    EXPECT_THROW(client.upload_file(dir_.path() / "big.bin", state,
                                    [&](int64_t done, int64_t) {
                                      if (done >= 8 * chunk) throw SimulatedDrop{};
                                    }),
                 SimulatedDrop);
    EXPECT_EQ(client.stats().upload_body_bytes, 8 * chunk);
  }
  ASSERT_FALSE(fs::is_empty(state)) << "the upload id must be remembered";

  // Second run (a new process would do the same): resumes at 8 chunks.
  ApiClient client(config(chunk));
  std::vector<int64_t> reports;
  const std::string blob = client.upload_file(
      dir_.path() / "big.bin", state, [&](int64_t done, int64_t) { reports.push_back(done); });
  EXPECT_EQ(blob, keel::sha256_bytes(bytes));
  EXPECT_EQ(client.stats().upload_body_bytes, static_cast<int64_t>(bytes.size()) - 8 * chunk)
      << "completed bytes must not be sent again";
  ASSERT_FALSE(reports.empty());
  EXPECT_EQ(reports.front(), 8 * chunk);
  EXPECT_EQ(reports.back(), static_cast<int64_t>(bytes.size()));
  EXPECT_TRUE(fs::is_empty(state));

  // The server holds exactly these bytes.
  client.download("/v1/blobs/" + blob, dir_.path() / "back.bin", blob);
  EXPECT_EQ(read_file(dir_.path() / "back.bin"), bytes);
}

TEST_F(ServerIntegration, DownloadResumesFromAPartialFile) {
  const std::string bytes = random_bytes(3 << 20, 2);
  write_file(dir_.path() / "blob.bin", bytes);
  ApiClient client(config());
  const std::string blob = client.upload_file(dir_.path() / "blob.bin", dir_.path() / "state");
  const int64_t have = 1 << 20;
  write_file(dir_.path() / "out.bin.part", bytes.substr(0, have));
  client.download("/v1/blobs/" + blob, dir_.path() / "out.bin", blob);
  EXPECT_EQ(read_file(dir_.path() / "out.bin"), bytes);
  EXPECT_EQ(client.stats().download_body_bytes, static_cast<int64_t>(bytes.size()) - have);
  EXPECT_FALSE(fs::exists(dir_.path() / "out.bin.part"));
}

TEST_F(ServerIntegration, CorruptedDownloadFailsTheSha256Check) {
  const std::string bytes = random_bytes(2 << 20, 3);
  write_file(dir_.path() / "blob.bin", bytes);
  ApiClient client(config());
  const std::string blob = client.upload_file(dir_.path() / "blob.bin", dir_.path() / "state");
  std::string corrupt = bytes.substr(0, 1 << 20);
  corrupt[1000] ^= 0x55;
  write_file(dir_.path() / "out.bin.part", corrupt);
  try {
    client.download("/v1/blobs/" + blob, dir_.path() / "out.bin", blob);
    FAIL() << "expected a SHA-256 mismatch";
  } catch (const ApiCallError& e) {
    EXPECT_EQ(e.code(), "sha256_mismatch");
    EXPECT_NE(std::string(e.what()).find(blob), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_.path() / "out.bin"));
  EXPECT_FALSE(fs::exists(dir_.path() / "out.bin.part")) << "a corrupt part must not be resumed";
  // The next attempt starts clean and succeeds.
  client.download("/v1/blobs/" + blob, dir_.path() / "out.bin", blob);
  EXPECT_EQ(read_file(dir_.path() / "out.bin"), bytes);
}

TEST_F(ServerIntegration, ClientAndWorkerCallsRoundTrip) {
  ApiClient client(config());
  SubmitOptions submit;
  submit.mission_dir = make_mission("usv-a");
  submit.stages = {"ingest"};
  submit.cache_dir = dir_.path() / "cache";
  submit.show_progress = false;
  const SubmitResult first = submit_mission(client, submit);
  const int64_t sent = client.stats().upload_body_bytes;
  EXPECT_GT(sent, 0);
  const SubmitResult again = submit_mission(client, submit);
  EXPECT_EQ(client.stats().upload_body_bytes, sent) << "the bundle blob is on the server already";
  EXPECT_EQ(first.job.id, again.job.id) << "a re-run submit must not make a second job";
  EXPECT_EQ(first.mission.id, again.mission.id);
  EXPECT_EQ(first.job.state, proto::JobState::kQueued);
  ASSERT_EQ(client.list_missions("usv-").size(), 1u);
  EXPECT_EQ(client.list_jobs("queued").size(), 1u);

  // Worker side: lease, heartbeat with log lines, an artifact, stage and job completion.
  const auto lease = client.lease(proto::LeaseRequest{"test:1", 30});
  ASSERT_TRUE(lease.has_value());
  EXPECT_EQ(lease->job.id, first.job.id);
  EXPECT_FALSE(client.lease(proto::LeaseRequest{"test:2", 30}).has_value()) << "queue is empty";
  proto::Heartbeat beat{lease->lease_id, "ingest", 0.5, {"reading imu.csv", "200 samples"}};
  EXPECT_FALSE(client.heartbeat(first.job.id, beat).canceled);
  EXPECT_EQ(client.get_job(first.job.id).state, proto::JobState::kRunning);
  const proto::LogPage log = client.read_log(first.job.id, 0);
  ASSERT_EQ(log.lines.size(), 2u);
  EXPECT_EQ(log.lines[1].text, "200 samples");

  const std::string report = R"({"samples": 200})";
  write_file(dir_.path() / "report.json", report);
  const std::string blob = client.upload_file(dir_.path() / "report.json", dir_.path() / "state");
  client.register_artifact(first.job.id, {lease->lease_id, "ingest", "report.json", blob});
  client.complete_stage(first.job.id, "ingest",
                        {lease->lease_id, nlohmann::json{{"samples", 200}}, 0.1});
  EXPECT_EQ(client.finish_job(first.job.id, {lease->lease_id, ""}, true).state,
            proto::JobState::kSucceeded);

  const auto artifacts = client.list_artifacts(first.job.id);
  ASSERT_EQ(artifacts.size(), 1u);
  EXPECT_EQ(artifacts[0].sha256, keel::sha256_bytes(report));
  client.download("/v1/artifacts/" + artifacts[0].id, dir_.path() / "got" / "report.json",
                  artifacts[0].sha256);
  EXPECT_EQ(read_file(dir_.path() / "got" / "report.json"), report);

  try {
    client.cancel_job(first.job.id);
    FAIL() << "canceling a finished job must be refused";
  } catch (const ApiCallError& e) {
    EXPECT_EQ(e.status(), 409);
  }
  const auto batch = client.reprocess(proto::ReprocessRequest{{}, "usv-", {"ingest"}, {}});
  ASSERT_EQ(batch.jobs.size(), 1u);
  EXPECT_NE(batch.jobs[0].id, first.job.id);
  EXPECT_EQ(batch.batch.jobs, 1);
  EXPECT_EQ(batch.jobs[0].batch_id, batch.batch.id);
  EXPECT_EQ(client.get_batch(batch.batch.id).jobs_by_state.at("queued"), 1);
  EXPECT_EQ(client.list_batch_jobs(batch.batch.id).size(), 1u);
}

// Runs the keel CLI with the server's URL and token in the environment; returns the exit
// code and stdout.
std::pair<int, std::string> run_cli(const std::string& env, const std::string& args) {
  const std::string command = env + " " + kCliBinary + " " + args + " 2>/dev/null";
  FILE* pipe = ::popen(command.c_str(), "r");
  std::string out;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) out.append(buffer, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST_F(ServerIntegration, CliSubmitIsIdempotentAndExitCodesTellWhatWentWrong) {
  if (std::string(kCliBinary).empty() || !fs::exists(kCliBinary)) GTEST_SKIP() << "keel not built";
  const fs::path mission = make_mission("hull-b");
  const std::string env = "HOME=" + dir_.path().string() +
                          " XDG_CONFIG_HOME= XDG_CACHE_HOME= KEEL_URL=" + server_->url() +
                          " KEEL_TOKEN=" + server_->token();
  const auto first = run_cli(env, "submit -q " + mission.string());
  ASSERT_EQ(first.first, 0) << first.second;
  const auto again = run_cli(env, "submit -q " + mission.string());
  ASSERT_EQ(again.first, 0);
  EXPECT_EQ(first.second, again.second) << "the same job id both times";
  EXPECT_EQ(first.second.size(), first.second.find('\n') + 1) << "only the job id on stdout";

  const std::string job = first.second.substr(0, first.second.size() - 1);
  const auto status = run_cli(env, "status --json " + job);
  EXPECT_EQ(status.first, 0);
  EXPECT_EQ(nlohmann::json::parse(status.second)["state"], "queued");
  EXPECT_EQ(run_cli(env, "cancel " + job).first, 0);
  EXPECT_EQ(run_cli(env, "watch --interval 0.1 " + job).first, 5) << "canceled job";
  EXPECT_EQ(run_cli(env, "status no-such-job").first, 2) << "4xx";
  EXPECT_EQ(run_cli(env, "submit " + (dir_.path() / "absent").string()).first, 6) << "local file";
  EXPECT_EQ(run_cli(env, "submit --stages nope " + mission.string()).first, 1) << "usage";
  EXPECT_EQ(run_cli(env, "--token wrong jobs").first, 2) << "401";
  EXPECT_EQ(run_cli(env, "--url http://127.0.0.1:1 jobs").first, 3) << "unreachable";
}


// keel reprocess makes a batch; keel jobs --batch counts it by state (exit 4 once a job of
// it failed) and --follow returns when nothing of it is queued or running.
TEST_F(ServerIntegration, CliFollowsAReprocessBatch) {
  if (std::string(kCliBinary).empty() || !fs::exists(kCliBinary)) GTEST_SKIP() << "keel not built";
  const std::string env = "HOME=" + dir_.path().string() +
                          " XDG_CONFIG_HOME= XDG_CACHE_HOME= KEEL_URL=" + server_->url() +
                          " KEEL_TOKEN=" + server_->token();
  for (const char* name : {"usv-a", "usv-b", "usv-c"})
    ASSERT_EQ(run_cli(env, "submit -q " + make_mission(name).string()).first, 0);
  ApiClient client(config());
  for (const proto::Job& job : client.list_jobs("queued")) client.cancel_job(job.id);

  const auto reprocessed = run_cli(env, "reprocess --prefix usv- --stages ingest");
  ASSERT_EQ(reprocessed.first, 0);
  const std::vector<proto::Job> jobs = client.list_jobs("queued");
  ASSERT_EQ(jobs.size(), 3u);
  const std::string batch = jobs[0].batch_id;
  ASSERT_FALSE(batch.empty());
  for (const proto::Job& job : jobs) EXPECT_EQ(job.batch_id, batch);

  auto counts = run_cli(env, "jobs --batch " + batch);
  EXPECT_EQ(counts.first, 0) << counts.second;
  EXPECT_NE(counts.second.find("3 jobs, 3 queued, 0 running"), std::string::npos)
      << counts.second;

  // One succeeds, one fails, one is left queued: counts move, and a failure gives exit 4.
  auto finish_next = [&](bool succeeded) {
    const auto lease = client.lease(proto::LeaseRequest{"test:1", 30});
    ASSERT_TRUE(lease.has_value());
    client.finish_job(lease->job.id, {lease->lease_id, succeeded ? "" : "bad imu.csv"},
                      succeeded);
  };
  finish_next(true);
  finish_next(false);
  counts = run_cli(env, "jobs --batch " + batch);
  EXPECT_EQ(counts.first, 4) << counts.second;
  EXPECT_NE(counts.second.find("1 queued, 0 running, 1 succeeded, 1 failed"), std::string::npos)
      << counts.second;
  EXPECT_NE(counts.second.find("over 2 finished"), std::string::npos) << counts.second;

  // --follow prints until the last job is done (finished here while it follows).
  std::thread last([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(600));
    finish_next(true);
  });
  counts = run_cli(env, "jobs --batch " + batch + " --follow --interval 0.2");
  last.join();
  EXPECT_EQ(counts.first, 4) << "a job of the batch failed";
  EXPECT_NE(counts.second.find("2 succeeded, 1 failed"), std::string::npos) << counts.second;
  EXPECT_NE(counts.second.find("finished"), std::string::npos) << counts.second;
  EXPECT_EQ(run_cli(env, "jobs --batch b_0000000000000000").first, 2) << "unknown batch: 404";
}

}  // namespace
}  // namespace keel::client
