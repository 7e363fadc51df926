// The PostgreSQL queue under load (issue 14 targets), on a private PostgreSQL started here:
//   1. leases/s and lease latency (p50/p95/p99) with W concurrent workers, each leasing and
//      completing jobs as fast as it can (target >= 500 leases/s with 16 workers on 2 cores,
//      p99 <= 20 ms), beside the same run on SQLite;
//   2. a reprocess batch over M stored missions (create_batch, one transaction; target: the
//      request returns in <= 2 s for 10,000 missions);
//   3. change-feed latency between two replicas: a job created on one store heard by the
//      other's subscription (the long poll's wake-up), median and max over R jobs.
// Run: build/tests/bench/bench_pg_queue [--workers 16] [--jobs 20000] [--missions 10000]
//      [--fsync on|off] [--seconds 10]
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include <pqxx/pqxx>

#include "storage/pg_store.h"
#include "storage/store.h"
#include "tests/storage/pg_test_server.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using keel::storage::Store;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const size_t index = std::min(values.size() - 1, static_cast<size_t>(p * values.size()));
  return values[index];
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

struct LeaseFigures {
  double leases_per_s = 0, p50_ms = 0, p95_ms = 0, p99_ms = 0, max_ms = 0;
  size_t leases = 0;
};

// W threads lease and finish jobs for `seconds` (or until the queue is empty).
LeaseFigures lease_run(Store& store, int workers, double seconds) {
  std::vector<std::vector<double>> latencies(workers);
  std::atomic<bool> stop{false};
  std::vector<std::thread> threads;
  const auto start = Clock::now();
  for (int w = 0; w < workers; ++w)
    threads.emplace_back([&, w] {
      keel::proto::LeaseRequest request{"bench-" + std::to_string(w), 300};
      while (!stop) {
        const auto begin = Clock::now();
        auto lease = store.lease_job(request);
        latencies[w].push_back(ms_since(begin));
        if (!lease) break;
        store.finish_job(lease->job.id, {lease->lease_id, ""}, true);
      }
    });
  while (ms_since(start) < seconds * 1000) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    bool all_done = true;
    for (auto& t : threads) all_done &= !t.joinable();
    if (all_done) break;
  }
  stop = true;
  for (auto& t : threads) t.join();
  const double elapsed_s = ms_since(start) / 1000;
  std::vector<double> all;
  for (const auto& l : latencies) all.insert(all.end(), l.begin(), l.end());
  LeaseFigures figures;
  figures.leases = all.size();
  figures.leases_per_s = all.size() / elapsed_s;
  figures.p50_ms = percentile(all, 0.50);
  figures.p95_ms = percentile(all, 0.95);
  figures.p99_ms = percentile(all, 0.99);
  figures.max_ms = percentile(all, 1.0);
  return figures;
}

// `missions` stored missions (one blob), then one job per mission in one batch. On
// PostgreSQL (`url` set) the missions are inserted by one SQL statement: the setup is not
// what is measured.
double fill(Store& store, int missions, const std::string& name_prefix,
            const std::string& url = "") {
  keel::proto::MissionRequest mission;
  mission.bundle_blob = store.put_blob("bundle");
  if (!url.empty()) {
    pqxx::connection connection(url);
    pqxx::work work(connection);
    work.exec_params(
        "INSERT INTO missions (id, name, bundle_blob, created_at_ms, project) "
        "SELECT 'm_' || lpad(to_hex(i), 16, '0'), $1 || i, $2, 0, 'default' "
        "FROM generate_series(1, $3) AS i",
        name_prefix, mission.bundle_blob, missions);
    work.commit();
  } else {
    for (int i = 0; i < missions; ++i) {
      mission.name = name_prefix + std::to_string(i);
      store.create_mission(mission);
    }
  }
  keel::proto::ReprocessRequest request;
  request.name_prefix = name_prefix;
  request.stages = {"ingest"};
  const auto start = Clock::now();
  const keel::proto::Batch batch = store.create_batch(request);
  const double ms = ms_since(start);
  if (batch.jobs != missions) std::fprintf(stderr, "batch made %ld jobs\n", long(batch.jobs));
  return ms;
}

void print_leases(const char* what, const LeaseFigures& f) {
  std::printf(
      "%-34s %8.0f leases/s  p50 %6.2f ms  p95 %6.2f ms  p99 %6.2f ms  max %7.2f ms  (%zu)\n", what,
      f.leases_per_s, f.p50_ms, f.p95_ms, f.p99_ms, f.max_ms, f.leases);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"PostgreSQL queue benchmark (issue 14 targets)"};
  int workers = 16, jobs = 20000, missions = 10000, wakeups = 50;
  double seconds = 10;
  std::string fsync = "on";
  bool skip_sqlite = false;
  app.add_option("--workers", workers)->capture_default_str();
  app.add_option("--jobs", jobs, "jobs queued before the lease run")->capture_default_str();
  app.add_option("--missions", missions, "missions of the reprocess batch")->capture_default_str();
  app.add_option("--seconds", seconds, "longest lease run")->capture_default_str();
  app.add_option("--wakeups", wakeups, "jobs timed through the change feed")->capture_default_str();
  app.add_option("--fsync", fsync, "PostgreSQL fsync (on = durable commits)")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  app.add_flag("--skip-sqlite", skip_sqlite, "no SQLite comparison run");
  CLI11_PARSE(app, argc, argv);

  if (keel::testing::PgTestServer::find_binaries().empty()) {
    std::printf("PostgreSQL is not installed: nothing to measure\n");
    return 0;
  }
  std::printf("load average at start: %s (%u cores)\n", load_average().c_str(),
              std::thread::hardware_concurrency());
  keel::testing::PgTestServer::Options server_options;
  server_options.fsync = fsync == "on";
  keel::testing::PgTestServer server(server_options);
  const fs::path blobs =
      fs::temp_directory_path() / ("keel-pg-bench-" + std::to_string(::getpid()));

  auto open_pg = [&](const std::string& url) {
    keel::storage::PgStoreOptions options;
    options.database_url = url;
    options.blob_dir = blobs;
    options.max_connections = static_cast<size_t>(workers) + 4;
    return std::unique_ptr<Store>(
        std::make_unique<keel::storage::PgStore>(options, keel::storage::system_clock_ms));
  };

  // 1. leases
  {
    const std::string url = server.create_database("leases");
    auto store = open_pg(url);
    fill(*store, jobs, "lease-", url);
    char label[64];
    std::snprintf(label, sizeof(label), "PostgreSQL, %d workers, fsync %s", workers, fsync.c_str());
    print_leases(label, lease_run(*store, workers, seconds));
    if (!skip_sqlite) {
      const fs::path dir = blobs / "sqlite";
      auto sqlite = keel::storage::open_sqlite_store(dir);
      fill(*sqlite, std::min(jobs, 5000), "lease-");
      std::snprintf(label, sizeof(label), "SQLite, %d workers", workers);
      print_leases(label, lease_run(*sqlite, workers, seconds));
    }
  }
  // 2. reprocess
  {
    const std::string url = server.create_database("reprocess");
    auto store = open_pg(url);
    const double ms = fill(*store, missions, "survey-", url);
    std::printf("reprocess batch over %d missions (create_batch): %.0f ms\n", missions, ms);
  }
  // 3. change feed between two replicas
  {
    const std::string url = server.create_database("feed");
    auto writer = open_pg(url);
    auto reader = open_pg(url);
    keel::proto::MissionRequest mission_request;
    mission_request.name = "feed";
    mission_request.bundle_blob = writer->put_blob("bundle");
    const auto mission = writer->create_mission(mission_request);
    std::mutex mutex;
    std::condition_variable heard;
    std::string last;
    auto subscription = reader->subscribe([&](const keel::storage::Change& change) {
      std::lock_guard<std::mutex> lock(mutex);
      last = change.job_id;
      heard.notify_all();
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the LISTEN is up
    std::vector<double> delays;
    for (int i = 0; i < wakeups; ++i) {
      const auto start = Clock::now();
      keel::proto::JobRequest request;
      request.mission_id = mission.id;
      request.stages = {"ingest"};
      const auto job = writer->create_job(request, "");
      std::unique_lock<std::mutex> lock(mutex);
      if (!heard.wait_for(lock, std::chrono::seconds(5), [&] { return last == job.id; })) {
        std::printf("change of %s not heard within 5 s\n", job.id.c_str());
        continue;
      }
      delays.push_back(ms_since(start));
    }
    std::printf(
        "change feed, create_job on replica A -> heard on B: median %.2f ms, p95 %.2f ms, "
        "max %.2f ms (%zu jobs; create_job's own commit included)\n",
        percentile(delays, 0.5), percentile(delays, 0.95), percentile(delays, 1.0), delays.size());
  }
  std::printf("load average at end: %s\n", load_average().c_str());
  std::error_code ignored;
  fs::remove_all(blobs, ignored);
  return 0;
}
