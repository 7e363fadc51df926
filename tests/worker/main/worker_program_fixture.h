// A test fixture that runs `keel-worker` as a program in a fresh temporary folder and
// captures its exit code, stdout and stderr. The test target defines KEEL_WORKER_BIN.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/temp_dir.h"

namespace keel::testing {

struct ProgramOutput {
  int code = -1;
  std::string out, err;
};

class WorkerProgramTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(worker_)) GTEST_SKIP() << worker_ << " not built";
    dir_ = std::filesystem::temp_directory_path() /
           ("keel_worker_cli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Runs keel-worker with `args` (each single-quoted for the shell).
  ProgramOutput run(const std::vector<std::string>& args) {
    std::string command = worker_.string();
    for (const auto& a : args) command += " '" + a + "'";
    command += " >" + (dir_ / "out.txt").string() + " 2>" + (dir_ / "err.txt").string();
    ProgramOutput o;
    const int status = std::system(command.c_str());
    o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    o.out = read_file(dir_ / "out.txt");
    o.err = read_file(dir_ / "err.txt");
    return o;
  }

  const std::filesystem::path worker_ = KEEL_WORKER_BIN;
  std::filesystem::path dir_;
};

}  // namespace keel::testing
