// Starts the real keel-server on 127.0.0.1:0 with its own data folder and no workers,
// and stops it (SIGTERM, then SIGKILL after 10 s) when destroyed.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace keel::client::testing {

class ServerProcess {
 public:
  ServerProcess(const std::filesystem::path& binary, const std::filesystem::path& data_dir)
      : data_dir_(data_dir) {
    std::filesystem::create_directories(data_dir);
    const std::string log = (data_dir.parent_path() / "server.log").string();
    std::vector<std::string> args = {
        binary.string(), "--data-dir", data_dir.string(), "--listen", "127.0.0.1:0",
        "--workers",     "0"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    const int rc = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) throw std::runtime_error("cannot start " + binary.string());
    wait_until_listening(log);
  }
  ~ServerProcess() {
    ::kill(pid_, SIGTERM);
    for (int i = 0; i < 100; ++i) {
      if (::waitpid(pid_, nullptr, WNOHANG) == pid_) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  const std::string& url() const { return url_; }
  const std::string& token() const { return token_; }

 private:
  static std::string first_line(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::string line;
    std::getline(in, line);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    return line;
  }

  void wait_until_listening(const std::string& log) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_)
        throw std::runtime_error("keel-server exited early; see " + log);
      url_ = first_line(data_dir_ / "server.url");
      token_ = first_line(data_dir_ / "token");
      if (!url_.empty() && !token_.empty()) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    throw std::runtime_error("keel-server did not write server.url within 20 s; see " + log);
  }

  std::filesystem::path data_dir_;
  pid_t pid_ = -1;
  std::string url_;
  std::string token_;
};

}  // namespace keel::client::testing
