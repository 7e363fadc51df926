// Shared helpers for the storage tests: a fresh data directory per test, a clock the test
// moves by hand, and a store with a mission ready for jobs.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>

#include "storage/store.h"

namespace keel::storage::testing {

// A temporary folder removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    std::random_device device;
    path_ = std::filesystem::temp_directory_path() /
            ("keel-storage-test-" + std::to_string(device()) + std::to_string(device()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Time that only moves when the test says so.
class FakeClock {
 public:
  explicit FakeClock(int64_t start_ms = 1'700'000'000'000)
      : now_ms_(std::make_shared<std::atomic<int64_t>>(start_ms)) {}
  Clock clock() const {
    auto now = now_ms_;
    return [now] { return now->load(); };
  }
  void advance_ms(int64_t ms) { *now_ms_ += ms; }
  int64_t now_ms() const { return now_ms_->load(); }

 private:
  std::shared_ptr<std::atomic<int64_t>> now_ms_;
};

inline std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline void write_file(const std::filesystem::path& file, const std::string& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Deterministic pseudo-random bytes (different seeds give different content).
inline std::string random_bytes(size_t size, unsigned seed) {
  std::mt19937 generator(seed);
  std::string bytes(size, '\0');
  for (char& c : bytes) c = static_cast<char>(generator() & 0xff);
  return bytes;
}

// A store in a fresh folder with a fake clock.
class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override { reopen(); }
  void reopen() {
    store_.reset();
    store_ = open_sqlite_store(dir_.path(), clock_.clock());
  }
  proto::Mission make_mission(const std::string& name = "bridge-01") {
    proto::MissionRequest request;
    request.name = name;
    request.bundle_blob = store_->put_blob("bundle of " + name);
    return store_->create_mission(request);
  }
  proto::JobRequest job_request(const proto::Mission& mission,
                                std::vector<std::string> stages = {"ingest", "refine", "map"}) {
    proto::JobRequest request;
    request.mission_id = mission.id;
    request.stages = std::move(stages);
    return request;
  }
  proto::Lease lease(const std::string& worker = "host:1", int lease_seconds = 30) {
    auto lease = store_->lease_job({worker, lease_seconds});
    if (!lease) throw std::runtime_error("expected a job to lease");
    return *lease;
  }

  TempDir dir_;
  FakeClock clock_;
  std::unique_ptr<Store> store_;
};

}  // namespace keel::storage::testing
