// A child process for the program tests: stdout and stderr into files (one file when `err` is
// `out`), wait with a deadline, signals. The destructor SIGKILLs a child still running.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace keel::testing {

class Child {
 public:
  Child(const std::filesystem::path& program, const std::vector<std::string>& args,
        const std::filesystem::path& out, const std::filesystem::path& err,
        const std::vector<std::string>& env = {}) {
    pid_ = ::fork();
    if (pid_ == 0) {
      if (!std::freopen(out.c_str(), "w", stdout) ||
          (err == out ? ::dup2(1, 2) < 0 : !std::freopen(err.c_str(), "w", stderr)))
        ::_exit(126);
      for (const auto& item : env) ::putenv(const_cast<char*>(item.c_str()));
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(program.c_str()));
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(program.c_str(), argv.data());
      ::_exit(127);
    }
  }
  ~Child() {
    if (pid_ > 0 && !status_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  pid_t pid() const { return pid_; }
  void signal(int signo) {
    if (!status_) ::kill(pid_, signo);
  }
  // The exit code (128 + signal when killed), or -1 when still running after `timeout`.
  int wait(std::chrono::milliseconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (!status_) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        break;
      }
      if (std::chrono::steady_clock::now() > until) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return *status_;
  }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
};

}  // namespace keel::testing
