// `keel-worker` as a program: `run` on tiny missions written here (exit codes 0, 1, 2, 130)
// and `serve` with no server to talk to (keeps retrying, exits 0 on SIGTERM).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "tests/child_process.h"
#include "tests/temp_dir.h"
#include "tests/worker/pipeline/test_missions.h"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const fs::path kWorker = KEEL_WORKER_BIN;

using keel::testing::read_file;

// keel-worker with stdout and stderr in files.
class Child : public keel::testing::Child {
 public:
  Child(const std::vector<std::string>& args, const fs::path& out, const fs::path& err,
        const std::vector<std::string>& env = {})
      : keel::testing::Child(kWorker, args, out, err, env) {}
};

class WorkerCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kWorker)) GTEST_SKIP() << kWorker << " not built";
    dir_ = fs::temp_directory_path() /
           ("keel_worker_cli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write_tiny_mission() {
    keel::testing::write_tiny_mission(dir_ / "mission");
    return dir_ / "mission";
  }

  int run(const std::vector<std::string>& args) {
    Child child(args, dir_ / "stdout.txt", dir_ / "stderr.txt");
    return child.wait(120s);
  }
  std::string err() const { return read_file(dir_ / "stderr.txt"); }

  fs::path dir_;
};

TEST_F(WorkerCliTest, RunWritesTheReportAndExitsZero) {
  const fs::path mission = write_tiny_mission();
  const fs::path out = dir_ / "out";
  ASSERT_EQ(
      run({"run", "--mission", mission.string(), "--stages", "ingest", "--out", out.string()}), 0)
      << err();

  const auto report = nlohmann::json::parse(read_file(out / "report.json"));
  EXPECT_EQ(report["keel_report"], 1);
  EXPECT_EQ(report["job"]["stages"], nlohmann::json::array({"ingest"}));
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["imu"]["count"], 6);
  EXPECT_EQ(report["stages"]["ingest"]["trajectories"]["odometry"]["count"], 4);
  EXPECT_GE(report["stage_seconds"]["ingest"].get<double>(), 0.0);
  const std::string printed = read_file(dir_ / "stdout.txt");
  EXPECT_NE(printed.find("[ingest] 100%"), std::string::npos) << printed;
}

TEST_F(WorkerCliTest, RunAcceptsABundleTar) {
  const fs::path mission = write_tiny_mission();
  const std::string tar = (dir_ / "bundle.tar").string();
  ASSERT_EQ(std::system(("tar -C " + dir_.string() + " -cf " + tar + " mission").c_str()), 0);
  const fs::path out = dir_ / "out";
  ASSERT_EQ(run({"run", "--mission", tar, "--stages", "ingest", "--out", out.string()}), 0)
      << err();
  const auto report = nlohmann::json::parse(read_file(out / "report.json"));
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["imu"]["count"], 6);
}

TEST_F(WorkerCliTest, StageFailureExitsTwoWithTheStageMessage) {
  const fs::path mission = write_tiny_mission();
  fs::remove(mission / "imu.csv");
  const fs::path out = dir_ / "out";
  EXPECT_EQ(
      run({"run", "--mission", mission.string(), "--stages", "ingest", "--out", out.string()}), 2);
  EXPECT_NE(err().find("ingest: "), std::string::npos) << err();
  EXPECT_NE(err().find("imu.csv"), std::string::npos) << err();
  // The report says which stage failed and why, with no section for it.
  const auto report = nlohmann::json::parse(read_file(out / "report.json"));
  EXPECT_EQ(report["failed"]["stage"], "ingest");
  EXPECT_NE(report["failed"]["error"].get<std::string>().find("imu.csv"), std::string::npos);
  EXPECT_TRUE(report["stages"].empty());
  const std::string html = read_file(out / "report.html");
  EXPECT_NE(html.find("id=\"failure\""), std::string::npos);
  EXPECT_NE(html.find("imu.csv"), std::string::npos);
}

TEST_F(WorkerCliTest, BadStageOptionFailsTheStage) {
  const fs::path mission = write_tiny_mission();
  EXPECT_EQ(run({"run", "--mission", mission.string(), "--stages", "ingest", "--out",
                 (dir_ / "out").string(), "--set", "ingest.no_such_option=1"}),
            2);
  EXPECT_NE(err().find("ingest: "), std::string::npos) << err();
  EXPECT_NE(err().find("no_such_option"), std::string::npos) << err();
  EXPECT_NE(err().find("known: gap_factor, rate_tolerance"), std::string::npos) << err();
}

// `--set calibration.<sensor>.<key>=<pose>` (docs/calibration.md): used, reported, checked.
TEST_F(WorkerCliTest, RunTakesExtrinsicOverrides) {
  const fs::path mission = write_tiny_mission();
  const std::string out = (dir_ / "out").string();
  ASSERT_EQ(run({"run", "--mission", mission.string(), "--stages", "ingest", "--out", out, "--set",
                 R"(calibration.imu.T_body_sensor={"xyz_m":[1,2,3],"rpy_deg":[0,0,90]})"}),
            0)
      << err();
  EXPECT_EQ(err().find("warning"), std::string::npos) << err();
  const auto report = nlohmann::json::parse(read_file(dir_ / "out" / "report.json"));
  EXPECT_EQ(report["calibration"]["imu"]["source"], "override T_body_sensor");
  EXPECT_EQ(report["calibration"]["imu"]["T_body_sensor"]["translation"],
            nlohmann::json({1.0, 2.0, 3.0}));
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["imu"]["extrinsic"], "override T_body_sensor");

  EXPECT_EQ(run({"run", "--mission", mission.string(), "--stages", "ingest", "--out", out, "--set",
                 "calibration.imu.T_body_sensor=oops"}),
            1);
  EXPECT_NE(err().find("calibration.imu.T_body_sensor: expected a JSON pose"), std::string::npos)
      << err();
  EXPECT_EQ(run({"run", "--mission", mission.string(), "--stages", "ingest", "--out", out, "--set",
                 R"(calibration.sonr.T_body_sensor={"xyz_m":[0,0,0],"rpy_deg":[0,0,0]})"}),
            2);
  EXPECT_NE(err().find("ingest: calibration.sonr: no sensor 'sonr' in the mission (sensors: imu)"),
            std::string::npos)
      << err();
}

TEST_F(WorkerCliTest, UsageErrorsExitOne) {
  const fs::path mission = write_tiny_mission();
  const std::string out = (dir_ / "out").string();
  EXPECT_EQ(run({"run", "--mission", mission.string()}), 1);  // no --out
  EXPECT_EQ(run({"run", "--mission", (dir_ / "nope").string(), "--out", out}), 1);
  EXPECT_NE(err().find("not found"), std::string::npos) << err();
  EXPECT_EQ(run({"run", "--mission", mission.string(), "--out", out, "--stages", "ingest,warp"}),
            1);
  EXPECT_NE(err().find("warp"), std::string::npos) << err();
  EXPECT_EQ(run({"run", "--mission", mission.string(), "--out", out, "--set", "ingest"}), 1);
  EXPECT_EQ(run({"run", "--mission", mission.string(), "--out", out, "--cad",
                 (dir_ / "hull.ply").string()}),
            1);
  EXPECT_EQ(run({"frobnicate"}), 1);
}

TEST_F(WorkerCliTest, SigintDuringAStageExits130) {
  const fs::path m = dir_ / "mission";
  keel::testing::write_long_mission(m);
  const fs::path out = dir_ / "out";
  Child child({"run", "--mission", m.string(), "--stages", "ingest", "--out", out.string()},
              dir_ / "stdout.txt", dir_ / "stderr.txt");
  // Interrupt once the stage has started.
  for (int i = 0;
       i < 24000 && read_file(dir_ / "stdout.txt").find("[ingest] 0%") == std::string::npos; ++i)
    std::this_thread::sleep_for(5ms);
  child.signal(SIGINT);
  const int code = child.wait(120s);
  if (code == 0) GTEST_SKIP() << "ingest finished before SIGINT arrived (machine too fast)";
  EXPECT_EQ(code, 130) << err();
  EXPECT_NE(err().find("interrupted during ingest"), std::string::npos) << err();
  EXPECT_FALSE(fs::exists(out / "report.json"));
}

TEST_F(WorkerCliTest, ServeWithoutTokenExitsOne) {
  Child child({"--server", "http://127.0.0.1:9", "--cache-dir", (dir_ / "cache").string()},
              dir_ / "stdout.txt", dir_ / "stderr.txt", {"KEEL_TOKEN="});
  EXPECT_EQ(child.wait(30s), 1);
  EXPECT_NE((read_file(dir_ / "stdout.txt") + err()).find("no token"), std::string::npos);
}

TEST_F(WorkerCliTest, ServeKeepsRetryingAnUnreachableServerAndStopsCleanlyOnSigterm) {
  // Port 9 (discard) on loopback: nothing listens, every lease attempt fails to connect.
  Child child({"serve", "--server", "http://127.0.0.1:9", "--token", "t", "--cache-dir",
               (dir_ / "cache").string(), "--poll-seconds", "0.1"},
              dir_ / "stdout.txt", dir_ / "stderr.txt");
  // Signal only once it has retried (its stop handlers are in place by then; a loaded machine
  // may take seconds to get there), and check it is still retrying after that.
  auto retried = [&] {
    return (read_file(dir_ / "stdout.txt") + err()).find("lease failed") != std::string::npos;
  };
  for (int i = 0; i < 6000 && !retried(); ++i) std::this_thread::sleep_for(10ms);
  ASSERT_TRUE(retried()) << "no retry logged within 60 s: " << err();
  EXPECT_EQ(child.wait(1500ms), -1) << "exited although it should retry: " << err();
  child.signal(SIGTERM);
  EXPECT_EQ(child.wait(30s), 0) << err();
  EXPECT_TRUE(fs::is_directory(dir_ / "cache" / "blobs"));
}

}  // namespace
