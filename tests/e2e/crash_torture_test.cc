// Crash torture: keel-server is killed with SIGKILL at random moments (KEEL_TORTURE_ROUNDS
// rounds, 20 by default) while 4 clients upload and the server's 2 local workers run jobs
// that a fifth client keeps submitting. After every kill: PRAGMA integrity_check is ok and
// every blob's content hashes to its name; after every restart: no temporary file of the
// killed server is left. At the end every upload completed (resumed, not restarted) with
// its file's SHA-256 and every job succeeded exactly once (no duplicate job for an
// Idempotency-Key, no artifact registered twice).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "core/sha256.h"
#include "storage/sqlite_db.h"
#include "tests/e2e/cluster.h"

namespace keel::e2e {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

int rounds() {
  const char* text = std::getenv("KEEL_TORTURE_ROUNDS");
  return text ? std::max(1, std::atoi(text)) : 20;
}

void write_random_file(const fs::path& file, int64_t bytes, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::ofstream out(file, std::ios::binary);
  for (int64_t i = 0; i < bytes / 8; ++i) {
    const uint64_t word = rng();
    out.write(reinterpret_cast<const char*>(&word), sizeof(word));
  }
}

// Integrity of a stopped server's folder; returns the number of blobs checked.
int check_folder(const fs::path& data) {
  storage::DatabaseOptions read_only;
  read_only.query_only = true;
  {
    storage::Database db(data / "keel.db", read_only);
    auto check = db.cached("PRAGMA integrity_check");
    EXPECT_TRUE(check->step());
    EXPECT_EQ(check->column_text(0), "ok");
  }
  int blobs = 0;
  if (!fs::exists(data / "blobs")) return 0;
  for (const auto& entry : fs::recursive_directory_iterator(data / "blobs")) {
    if (!entry.is_regular_file()) continue;
    ++blobs;
    EXPECT_EQ(keel::sha256_file(entry.path()), entry.path().filename().string())
        << entry.path() << " holds other bytes than its name says";
  }
  return blobs;
}

std::set<fs::path> temp_files(const fs::path& data) {
  std::set<fs::path> out;
  if (fs::exists(data / "tmp"))
    for (const auto& entry : fs::directory_iterator(data / "tmp")) out.insert(entry.path());
  for (const auto& entry : fs::directory_iterator(data))
    if (entry.path().filename().string().find(".tmp.") != std::string::npos)
      out.insert(entry.path());
  return out;
}

client::ClientConfig patient_config(const Cluster& cluster) {
  client::ClientConfig config;
  config.url = cluster.url();
  config.token = cluster.token();
  config.chunk_bytes = 1 << 20;
  config.retries = 50;
  config.retry_backoff_s = 0.05;
  config.timeout_s = 30;
  return config;
}

// Calls `work` until it returns without an exception or `deadline` passes (the server is
// down now and then); the last error is rethrown.
template <typename Work>
auto keep_trying(Work work, std::chrono::steady_clock::time_point deadline) {
  for (;;) {
    try {
      return work();
    } catch (const client::ApiCallError& e) {
      if (std::chrono::steady_clock::now() > deadline) throw;
      std::this_thread::sleep_for(100ms);
    }
  }
}

TEST(CrashTorture, KillNineAtRandomWhileClientsUploadAndWorkersRunJobs) {
  TempDir root;
  const fs::path mission = root.path() / "mission";
  simulate_mission(mission, 4, "imu,dvl,depth");
  // Fixed port: clients reconnect to the restarted server. No rate limit: 5 clients share
  // the admin token.
  Cluster cluster(root.path(), /*workers=*/2, free_port(), {"--rate-limit", "0"});
  const auto deadline = std::chrono::steady_clock::now() + 600s;

  // The mission's bundle, uploaded once before the torture.
  const RunResult made =
      cluster.keel({"submit", mission.string(), "--stages", "ingest", "--wait", "-q"});
  ASSERT_EQ(made.exit_code, 0) << made.output;
  std::string mission_id;
  {
    client::ApiClient api(patient_config(cluster));
    const auto missions = api.list_missions();
    ASSERT_EQ(missions.size(), 1u);
    mission_id = missions[0].id;
  }

  std::atomic<bool> torturing{true};
  // Uploaders: 4 clients, 3 files of 6 MiB each, resumable through their state folders.
  constexpr int kUploaders = 4, kFiles = 3;
  std::mutex mutex;
  std::vector<std::string> upload_errors;
  std::vector<std::pair<std::string, std::string>> uploaded;  // expected, got
  std::vector<std::thread> threads;
  for (int u = 0; u < kUploaders; ++u) {
    threads.emplace_back([&, u] {
      client::ApiClient api(patient_config(cluster));
      for (int f = 0; f < kFiles; ++f) {
        const fs::path file = root.path() / ("up-" + std::to_string(u) + "-" + std::to_string(f));
        write_random_file(file, 6 << 20, 100 * u + f);
        const std::string expected = keel::sha256_file(file);
        try {
          const std::string blob = keep_trying(
              [&] { return api.upload_file(file, root.path() / ("state-" + std::to_string(u))); },
              deadline);
          std::lock_guard<std::mutex> lock(mutex);
          uploaded.emplace_back(expected, blob);
        } catch (const std::exception& e) {
          std::lock_guard<std::mutex> lock(mutex);
          upload_errors.push_back(file.filename().string() + ": " + e.what());
        }
      }
    });
  }
  // Submitter: a job every ~0.7 s while the torture lasts, each with its Idempotency-Key,
  // retried until the server answers (a retry after a crash must not make a second job).
  std::vector<std::string> job_ids;
  int jobs_asked = 0;
  threads.emplace_back([&] {
    client::ApiClient api(patient_config(cluster));
    while (torturing) {
      const std::string key = "torture-" + std::to_string(jobs_asked++);
      proto::JobRequest request;
      request.mission_id = mission_id;
      request.stages = {"ingest"};
      try {
        const proto::Job job = keep_trying([&] { return api.create_job(request, key); }, deadline);
        std::lock_guard<std::mutex> lock(mutex);
        job_ids.push_back(job.id);
      } catch (const std::exception& e) {
        ADD_FAILURE() << key << ": " << e.what();
      }
      std::this_thread::sleep_for(700ms);
    }
  });

  std::mt19937 rng(2026);
  std::uniform_int_distribution<int> pause_ms(300, 2500);
  int orphans_seen = 0;
  // A round that throws (the server not coming back, say) ends the torture as a failure;
  // the client threads are still joined, so the test reports it instead of aborting.
  bool stopped = false;
  try {
    for (int round = 0; round < rounds(); ++round) {
      std::this_thread::sleep_for(std::chrono::milliseconds(pause_ms(rng)));
      cluster.kill_server();
      check_folder(cluster.data_dir());
      const std::set<fs::path> orphans = temp_files(cluster.data_dir());
      orphans_seen += static_cast<int>(orphans.size());
      cluster.start_server();
      for (const fs::path& orphan : orphans)
        EXPECT_FALSE(fs::exists(orphan))
            << "round " << round << ": " << orphan << " survived a restart";
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "the torture stopped: " << e.what();
    stopped = true;
    torturing = false;
    try {
      cluster.start_server();  // let the clients finish (or give up) against a live server
    } catch (const std::exception&) {
    }
  }
  torturing = false;
  for (auto& thread : threads) thread.join();
  if (stopped) return;

  EXPECT_TRUE(upload_errors.empty()) << upload_errors.front();
  EXPECT_EQ(uploaded.size(), static_cast<size_t>(kUploaders * kFiles));
  for (const auto& [expected, got] : uploaded) EXPECT_EQ(got, expected);

  client::ApiClient api(patient_config(cluster));
  const std::set<std::string> distinct(job_ids.begin(), job_ids.end());
  EXPECT_EQ(distinct.size(), job_ids.size()) << "a retried create made a second job";
  EXPECT_EQ(static_cast<int>(api.list_jobs().size()), jobs_asked + 1);  // + the first submit
  int succeeded = 0;
  for (const std::string& id : job_ids) {
    const proto::Job job = wait_job(
        api, id, [](const proto::Job& j) { return proto::is_terminal(j.state); }, 300);
    EXPECT_EQ(job.state, proto::JobState::kSucceeded) << id << ": " << job.error;
    succeeded += job.state == proto::JobState::kSucceeded;
    std::set<std::string> names;
    for (const proto::Artifact& artifact : api.list_artifacts(id))
      EXPECT_TRUE(names.insert(artifact.name).second)
          << id << ": artifact " << artifact.name << " twice";
  }
  cluster.stop_server();
  const int blobs = check_folder(cluster.data_dir());
  std::cout << rounds() << " kill -9 rounds: " << uploaded.size()
            << " uploads resumed to the right SHA-256, " << succeeded << "/" << job_ids.size()
            << " jobs succeeded once, " << blobs << " blobs whole, " << orphans_seen
            << " temporary files of killed servers removed\n";
}

}  // namespace
}  // namespace keel::e2e
