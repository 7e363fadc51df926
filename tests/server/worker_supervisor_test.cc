// The supervisor with shell scripts standing in for keel-worker.
#include "server/worker_supervisor.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <sstream>
#include <thread>

#include "tests/server/handler_fixture.h"

namespace keel::server::testing {
namespace {

using namespace std::chrono_literals;

bool eventually(const std::function<bool()>& condition,
                std::chrono::milliseconds limit = 10'000ms) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return condition();
}

bool process_exists(pid_t pid) { return pid > 0 && kill(pid, 0) == 0; }

class SupervisorTest : public ::testing::Test {
 protected:
  std::filesystem::path script(const std::string& name, const std::string& body) {
    std::filesystem::path path = dir_.path() / name;
    std::ofstream(path) << "#!/bin/sh\n" << body << "\n";
    chmod(path.c_str(), 0755);
    return path;
  }
  SupervisorOptions options(const std::filesystem::path& binary, int workers) {
    SupervisorOptions o;
    o.workers = workers;
    o.worker_binary = binary;
    o.log_dir = dir_.path() / "logs";
    o.initial_backoff = 50ms;
    o.max_backoff = 200ms;
    o.stop_grace = 500ms;
    o.poll_interval = 20ms;
    return o;
  }
  std::string read(const std::filesystem::path& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  TempDir dir_;
};

TEST_F(SupervisorTest, StartsWorkersWithArgsAndLogsAndRestartsACrashedOne) {
  auto binary = script("worker.sh", "echo \"worker args: $*\"\nexec sleep 60");
  WorkerSupervisor supervisor(options(binary, 2));
  supervisor.start({"--server", "http://127.0.0.1:1234", "--token-file", "/x/token"});
  EXPECT_EQ(supervisor.alive(), 2);
  const std::vector<pid_t> first = supervisor.pids();
  ASSERT_EQ(first.size(), 2u);
  for (pid_t pid : first) EXPECT_TRUE(process_exists(pid));
  const auto log0 = dir_.path() / "logs" / "worker-0.log";
  ASSERT_TRUE(eventually([&] { return read(log0).find("worker args") != std::string::npos; }));
  EXPECT_NE(read(log0).find("worker args: --server http://127.0.0.1:1234 --token-file /x/token"),
            std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir_.path() / "logs" / "worker-1.log"));

  kill(first[0], SIGKILL);
  ASSERT_TRUE(eventually([&] {
    auto now = supervisor.pids();
    return now[0] != 0 && now[0] != first[0];
  }));
  EXPECT_EQ(supervisor.restarts(), 1);
  EXPECT_EQ(supervisor.pids()[1], first[1]);  // the other one untouched
  EXPECT_EQ(supervisor.alive(), 2);

  const std::vector<pid_t> last = supervisor.pids();
  supervisor.stop();
  EXPECT_EQ(supervisor.alive(), 0);
  for (pid_t pid : last) EXPECT_FALSE(process_exists(pid)) << pid;  // reaped, not zombies
}

// A worker that outlives a killed server must not hold the server's listening socket (or any
// other descriptor of the server's), or the restarted server cannot bind its port.
TEST_F(SupervisorTest, WorkersInheritOnlyStdinStdoutAndStderr) {
  const int inherited = ::dup(STDERR_FILENO);  // a descriptor without close-on-exec
  ASSERT_GE(inherited, 3);
  // The shell lists its own descriptors with ls writing straight to the log: a pipeline would
  // list the shell's transient pipe ends too (seen under load: "0 1 2 4 10").
  auto binary = script("fds.sh", "ls /proc/$$/fd\necho end\nexec sleep 60");
  WorkerSupervisor supervisor(options(binary, 1));
  supervisor.start({});
  ::close(inherited);
  const auto log = dir_.path() / "logs" / "worker-0.log";
  ASSERT_TRUE(eventually([&] { return read(log).find("end\n") != std::string::npos; }));
  std::set<int> fds;
  std::istringstream lines(read(log));
  for (std::string line; std::getline(lines, line) && line != "end";) fds.insert(std::stoi(line));
  for (const int fd : {0, 1, 2}) EXPECT_EQ(fds.count(fd), 1u) << read(log);
  // The shell's own descriptor for reading its script may be there too (dash keeps it at 10).
  EXPECT_EQ(fds.count(inherited), 0u)
      << "descriptor " << inherited << " of the server reached the worker: " << read(log);
  supervisor.stop();
}

TEST_F(SupervisorTest, WorkerIgnoringSigtermIsKilledAfterTheGrace) {
  auto binary = script("stubborn.sh", "trap '' TERM\nwhile :; do sleep 0.05; done");
  WorkerSupervisor supervisor(options(binary, 1));
  supervisor.start({});
  const pid_t pid = supervisor.pids()[0];
  ASSERT_TRUE(process_exists(pid));
  std::this_thread::sleep_for(100ms);  // let the trap be installed
  supervisor.stop();
  EXPECT_FALSE(process_exists(pid));
  EXPECT_EQ(supervisor.restarts(), 0);
}

TEST_F(SupervisorTest, AWorkerThatKeepsExitingIsRestartedWithBackoff) {
  auto binary = script("crash.sh", "echo crashing; exit 3");
  WorkerSupervisor supervisor(options(binary, 1));
  supervisor.start({});
  ASSERT_TRUE(eventually([&] { return supervisor.restarts() >= 3; }));
  supervisor.stop();
  std::string log = read(dir_.path() / "logs" / "worker-0.log");
  size_t count = 0;
  for (size_t pos = 0; (pos = log.find("crashing", pos)) != std::string::npos; ++pos) ++count;
  EXPECT_GE(count, 3u);  // appended, not truncated
}

TEST_F(SupervisorTest, ZeroWorkersStartsNothingAndMissingBinaryFails) {
  WorkerSupervisor none(options(dir_.path() / "absent", 0));
  EXPECT_NO_THROW(none.start({}));
  EXPECT_EQ(none.alive(), 0);
  WorkerSupervisor missing(options(dir_.path() / "absent", 1));
  EXPECT_THROW(missing.start({}), std::runtime_error);
}

}  // namespace
}  // namespace keel::server::testing
