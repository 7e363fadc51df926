// A test fixture that runs `keel-worker` as a program in a fresh temporary folder and
#include "tests/temp_dir.h"
// captures its exit code, stdout and stderr. The test target defines KEEL_WORKER_BIN.
#include "tests/temp_dir.h"
#pragma once
#include "tests/temp_dir.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include "tests/temp_dir.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>
#include "tests/temp_dir.h"

#include "tests/temp_dir.h"
namespace keel::testing {
#include "tests/temp_dir.h"

#include "tests/temp_dir.h"
struct ProgramOutput {
#include "tests/temp_dir.h"
  int code = -1;
#include "tests/temp_dir.h"
  std::string out, err;
#include "tests/temp_dir.h"
};
#include "tests/temp_dir.h"

#include "tests/temp_dir.h"

#include "tests/temp_dir.h"
class WorkerProgramTest : public ::testing::Test {
#include "tests/temp_dir.h"
 protected:
#include "tests/temp_dir.h"
  void SetUp() override {
#include "tests/temp_dir.h"
    if (!std::filesystem::exists(worker_)) GTEST_SKIP() << worker_ << " not built";
#include "tests/temp_dir.h"
    dir_ = std::filesystem::temp_directory_path() /
#include "tests/temp_dir.h"
           ("keel_worker_cli_" + std::to_string(::getpid()) + "_" +
#include "tests/temp_dir.h"
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
#include "tests/temp_dir.h"
    std::filesystem::remove_all(dir_);
#include "tests/temp_dir.h"
    std::filesystem::create_directories(dir_);
#include "tests/temp_dir.h"
  }
#include "tests/temp_dir.h"
  void TearDown() override { std::filesystem::remove_all(dir_); }
#include "tests/temp_dir.h"

#include "tests/temp_dir.h"
  // Runs keel-worker with `args` (each single-quoted for the shell).
#include "tests/temp_dir.h"
  ProgramOutput run(const std::vector<std::string>& args) {
#include "tests/temp_dir.h"
    std::string command = worker_.string();
#include "tests/temp_dir.h"
    for (const auto& a : args) command += " '" + a + "'";
#include "tests/temp_dir.h"
    command += " >" + (dir_ / "out.txt").string() + " 2>" + (dir_ / "err.txt").string();
#include "tests/temp_dir.h"
    ProgramOutput o;
#include "tests/temp_dir.h"
    const int status = std::system(command.c_str());
#include "tests/temp_dir.h"
    o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
#include "tests/temp_dir.h"
    o.out = read_file(dir_ / "out.txt");
#include "tests/temp_dir.h"
    o.err = read_file(dir_ / "err.txt");
#include "tests/temp_dir.h"
    return o;
#include "tests/temp_dir.h"
  }
#include "tests/temp_dir.h"

#include "tests/temp_dir.h"
  const std::filesystem::path worker_ = KEEL_WORKER_BIN;
#include "tests/temp_dir.h"
  std::filesystem::path dir_;
#include "tests/temp_dir.h"
};
#include "tests/temp_dir.h"

#include "tests/temp_dir.h"
}  // namespace keel::testing
#include "tests/temp_dir.h"
