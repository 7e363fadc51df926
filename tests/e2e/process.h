// Child processes for end-to-end tests: spawn, wait with a deadline, signal.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tests/temp_dir.h"

namespace keel::e2e {

class Process {
 public:
  // Starts `argv[0]` with arguments; stdout and stderr go to `log_file` (appended).
  Process(std::vector<std::string> argv, const std::filesystem::path& log_file,
          const std::vector<std::string>& extra_env = {});
  ~Process();  // SIGKILLs and reaps a child still running
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }
  void signal(int signo);
  // Exit code (128 + signal for a signalled child), or nullopt when still running at the deadline.
  std::optional<int> wait_for(std::chrono::milliseconds timeout);
  bool running();

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
};

struct RunResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// Runs a command to completion (or kills it after `timeout`) and captures its output.
RunResult run_command(const std::vector<std::string>& argv, std::chrono::seconds timeout,
                      const std::vector<std::string>& extra_env = {});

using keel::testing::read_file;
// Polls until `file` exists and is non-empty, or the timeout passes.
bool wait_for_file(const std::filesystem::path& file, std::chrono::milliseconds timeout);

}  // namespace keel::e2e
