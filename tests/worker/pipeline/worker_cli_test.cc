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

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const fs::path kWorker = fs::path(KEEL_BINARY_DIR) / "worker" / "main" / "keel-worker";

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A child process with stdout and stderr in files.
class Child {
 public:
  Child(const std::vector<std::string>& args, const fs::path& out, const fs::path& err,
        const std::vector<std::string>& env = {}) {
    pid_ = ::fork();
    if (pid_ == 0) {
      std::freopen(out.c_str(), "w", stdout);
      std::freopen(err.c_str(), "w", stderr);
      for (const auto& item : env) ::putenv(const_cast<char*>(item.c_str()));
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(kWorker.c_str()));
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(kWorker.c_str(), argv.data());
      ::_exit(127);
    }
  }
  ~Child() {
    if (pid_ > 0 && !status_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  void signal(int signo) { ::kill(pid_, signo); }
  // The exit code, or -1 when still running after `timeout`.
  int wait(std::chrono::milliseconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (!status_) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        break;
      }
      if (std::chrono::steady_clock::now() > until) return -1;
      std::this_thread::sleep_for(5ms);
    }
    return *status_;
  }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
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

  // One IMU at 10 Hz with 6 samples and a 4-pose odometry: ingest counts are known.
  fs::path write_tiny_mission() {
    const fs::path m = dir_ / "mission";
    fs::create_directories(m);
    std::ofstream(m / "mission.yaml") << R"(keel_mission: 1
name: tiny
platform: usv
sensors:
  - name: imu
    type: imu
    file: imu.csv
    rate_hz: 10
    T_body_sensor: {translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 1]}
trajectories:
  odometry: odometry.tum
)";
    std::ofstream imu(m / "imu.csv");
    imu << "t,wx,wy,wz,ax,ay,az\n";
    for (int i = 0; i < 6; ++i) imu << "1700000000." << i << ",0,0,0.1,0,0,9.81\n";
    std::ofstream odometry(m / "odometry.tum");
    for (int i = 0; i < 4; ++i) odometry << "1700000000." << i << " " << i << " 0 0 0 0 0 1\n";
    return m;
  }

  int run(const std::vector<std::string>& args) {
    Child child(args, dir_ / "stdout.txt", dir_ / "stderr.txt");
    return child.wait(120s);
  }
  std::string err() const { return read_text(dir_ / "stderr.txt"); }

  fs::path dir_;
};

TEST_F(WorkerCliTest, RunWritesTheReportAndExitsZero) {
  const fs::path mission = write_tiny_mission();
  const fs::path out = dir_ / "out";
  ASSERT_EQ(run({"run", "--mission", mission.string(), "--out", out.string()}), 0) << err();

  const auto report = nlohmann::json::parse(read_text(out / "report.json"));
  EXPECT_EQ(report["keel_report"], 1);
  EXPECT_EQ(report["job"]["stages"], nlohmann::json::array({"ingest"}));
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["imu"]["count"], 6);
  EXPECT_EQ(report["stages"]["ingest"]["trajectories"]["odometry"]["count"], 4);
  EXPECT_GE(report["stage_seconds"]["ingest"].get<double>(), 0.0);
  const std::string printed = read_text(dir_ / "stdout.txt");
  EXPECT_NE(printed.find("[ingest] 100%"), std::string::npos) << printed;
}

TEST_F(WorkerCliTest, RunAcceptsABundleTar) {
  const fs::path mission = write_tiny_mission();
  const std::string tar = (dir_ / "bundle.tar").string();
  ASSERT_EQ(std::system(("tar -C " + dir_.string() + " -cf " + tar + " mission").c_str()), 0);
  const fs::path out = dir_ / "out";
  ASSERT_EQ(run({"run", "--mission", tar, "--stages", "ingest", "--out", out.string()}), 0)
      << err();
  const auto report = nlohmann::json::parse(read_text(out / "report.json"));
  EXPECT_EQ(report["stages"]["ingest"]["sensors"]["imu"]["count"], 6);
}

TEST_F(WorkerCliTest, StageFailureExitsTwoWithTheStageMessage) {
  const fs::path mission = write_tiny_mission();
  fs::remove(mission / "imu.csv");
  const fs::path out = dir_ / "out";
  EXPECT_EQ(run({"run", "--mission", mission.string(), "--out", out.string()}), 2);
  EXPECT_NE(err().find("ingest: "), std::string::npos) << err();
  EXPECT_NE(err().find("imu.csv"), std::string::npos) << err();
  EXPECT_FALSE(fs::exists(out / "report.json"));
}

TEST_F(WorkerCliTest, BadStageOptionFailsTheStage) {
  const fs::path mission = write_tiny_mission();
  EXPECT_EQ(run({"run", "--mission", mission.string(), "--out", (dir_ / "out").string(), "--set",
                 "ingest.no_such_option=1"}),
            2);
  EXPECT_NE(err().find("ingest: "), std::string::npos) << err();
  EXPECT_NE(err().find("no_such_option"), std::string::npos) << err();
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
  // 20000 scans (one file, indexed 20000 times): ingest checks for cancel between scans.
  const fs::path m = dir_ / "mission";
  fs::create_directories(m / "lidar");
  std::ofstream(m / "mission.yaml") << R"(keel_mission: 1
name: scans
platform: usv
sensors:
  - name: lidar
    type: lidar
    scans: lidar
    rate_hz: 10
    T_body_sensor: {translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 1]}
trajectories:
  odometry: odometry.tum
)";
  std::ofstream(m / "lidar" / "s.pcd")
      << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
         "WIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n0 0 1\n";
  {
    std::ofstream index(m / "lidar" / "index.csv");
    index << "t,file\n";
    for (int i = 0; i < 20000; ++i) index << 1700000000 + i / 10 << "." << i % 10 << ",s.pcd\n";
    std::ofstream odometry(m / "odometry.tum");
    for (int i = 0; i < 4; ++i) odometry << "1700000000." << i << " " << i << " 0 0 0 0 0 1\n";
  }
  const fs::path out = dir_ / "out";
  Child child({"run", "--mission", m.string(), "--out", out.string()}, dir_ / "stdout.txt",
              dir_ / "stderr.txt");
  // Interrupt once the stage has started.
  for (int i = 0;
       i < 24000 && read_text(dir_ / "stdout.txt").find("[ingest] 0%") == std::string::npos; ++i)
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
  EXPECT_NE((read_text(dir_ / "stdout.txt") + err()).find("no token"), std::string::npos);
}

TEST_F(WorkerCliTest, ServeKeepsRetryingAnUnreachableServerAndStopsCleanlyOnSigterm) {
  // Port 9 (discard) on loopback: nothing listens, every lease attempt fails to connect.
  Child child({"serve", "--server", "http://127.0.0.1:9", "--token", "t", "--cache-dir",
               (dir_ / "cache").string(), "--poll-seconds", "0.1"},
              dir_ / "stdout.txt", dir_ / "stderr.txt");
  EXPECT_EQ(child.wait(1500ms), -1) << "exited although it should retry: " << err();
  child.signal(SIGTERM);
  EXPECT_EQ(child.wait(30s), 0) << err();
  EXPECT_TRUE(fs::is_directory(dir_ / "cache" / "blobs"));
}

}  // namespace
