// Starts the real keel-server on 127.0.0.1:0 with its own data folder and no workers,
// and stops it (SIGTERM, then SIGKILL after 10 s) when destroyed.
#pragma once

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>

#include "tests/child_process.h"

namespace keel::client::testing {

class ServerProcess {
 public:
  ServerProcess(const std::filesystem::path& binary, const std::filesystem::path& data_dir)
      : data_dir_(created(data_dir)),
        log_(data_dir.parent_path() / "server.log"),
        child_(binary,
               {"--data-dir", data_dir.string(), "--listen", "127.0.0.1:0", "--workers", "0"}, log_,
               log_) {
    wait_until_listening();
  }
  ~ServerProcess() {
    child_.signal(SIGTERM);
    child_.wait(std::chrono::seconds(10));  // else the Child's destructor SIGKILLs it
  }

  const std::string& url() const { return url_; }
  const std::string& token() const { return token_; }

 private:
  static const std::filesystem::path& created(const std::filesystem::path& dir) {
    std::filesystem::create_directories(dir);
    return dir;
  }

  static std::string first_line(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::string line;
    std::getline(in, line);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    return line;
  }

  void wait_until_listening() {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (std::chrono::steady_clock::now() < deadline) {
      if (child_.wait(std::chrono::milliseconds(0)) >= 0)
        throw std::runtime_error("keel-server exited early; see " + log_.string());
      url_ = first_line(data_dir_ / "server.url");
      token_ = first_line(data_dir_ / "token");
      if (!url_.empty() && !token_.empty()) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    throw std::runtime_error("keel-server did not write server.url within 20 s; see " +
                             log_.string());
  }

  std::filesystem::path data_dir_;
  std::filesystem::path log_;
  keel::testing::Child child_;
  std::string url_;
  std::string token_;
};

}  // namespace keel::client::testing
