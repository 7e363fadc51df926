// bench_http: 64 concurrent keep-alive connections doing GET /v1/jobs/{id} for N seconds
// against an in-process keel-server (real SQLite store in a temporary folder), printing
// requests/s and latency percentiles. Targets: >= 10,000 req/s, p99 <= 10 ms on 2 cores
// (the load generator shares those cores).
//
//   bench_http [--seconds 5] [--connections 64] [--threads 2]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <thread>
#include <vector>

#include "server/http_handler.h"
#include "server/http_server.h"
#include "storage/store.h"
#include "tests/server/raw_http_client.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Result {
  std::vector<double> latencies_ms;
  int64_t errors = 0;
};

double percentile(std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0.0;
  size_t index = static_cast<size_t>(p * static_cast<double>(sorted.size() - 1) + 0.5);
  return sorted[std::min(index, sorted.size() - 1)];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"HTTP benchmark of keel-server: GET /v1/jobs/{id} over keep-alive connections"};
  double seconds = 5.0;
  int connections = 64;
  int threads = 2;
  app.add_option("--seconds", seconds, "duration of the measured run")
      ->check(CLI::Range(0.5, 600.0));
  app.add_option("--connections", connections, "concurrent keep-alive connections")
      ->check(CLI::Range(1, 1024));
  app.add_option("--threads", threads, "server io threads")->check(CLI::Range(1, 64));
  CLI11_PARSE(app, argc, argv);

  std::random_device device;
  const auto dir =
      std::filesystem::temp_directory_path() / ("keel-bench-http-" + std::to_string(device()));
  std::filesystem::create_directories(dir);
  int status = 0;
  {
    auto store = keel::storage::open_sqlite_store(dir);
    const std::string token = "bench-token";
    store->add_token(token, keel::storage::admin_token("bench"));
    keel::proto::MissionRequest mission_request;
    mission_request.name = "bench";
    mission_request.bundle_blob = store->put_blob("bench bundle");
    auto mission = store->create_mission(mission_request);
    keel::proto::JobRequest job_request;
    job_request.mission_id = mission.id;
    job_request.stages = {"ingest", "refine", "map"};
    const std::string job_id = store->create_job(job_request, "").id;

    keel::server::HttpHandler handler(*store);
    keel::server::ServerOptions options;
    options.port = 0;
    options.threads = threads;
    keel::server::HttpServer server(handler, options);
    server.start();
    const uint16_t port = server.port();
    const std::string request =
        keel::server::testing::http_request("GET", "/v1/jobs/" + job_id, token);

    std::atomic<bool> go{false};
    Clock::time_point stop_at;
    std::vector<Result> results(static_cast<size_t>(connections));
    std::vector<std::thread> clients;
    for (int i = 0; i < connections; ++i) {
      clients.emplace_back([&, i] {
        Result& result = results[static_cast<size_t>(i)];
        result.latencies_ms.reserve(1 << 16);
        keel::server::testing::RawClient client(port);
        while (!go) std::this_thread::yield();
        while (Clock::now() < stop_at) {
          const auto start = Clock::now();
          auto reply = client.exchange(request);
          const auto end = Clock::now();
          if (!reply || reply->status != 200) {
            ++result.errors;
            continue;
          }
          result.latencies_ms.push_back(
              std::chrono::duration<double, std::milli>(end - start).count());
        }
      });
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));  // connections established
    const auto started = Clock::now();
    stop_at = started +
              std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
    go = true;
    for (auto& client : clients) client.join();
    const double elapsed = std::chrono::duration<double>(Clock::now() - started).count();
    server.stop();

    std::vector<double> all;
    int64_t errors = 0;
    for (auto& result : results) {
      all.insert(all.end(), result.latencies_ms.begin(), result.latencies_ms.end());
      errors += result.errors;
    }
    std::sort(all.begin(), all.end());
    std::printf(
        "bench_http: GET /v1/jobs/{id}, %d keep-alive connections, %d server io threads, %.1f s\n",
        connections, threads, elapsed);
    std::printf("  requests   %zu (%lld errors)\n", all.size(), static_cast<long long>(errors));
    std::printf("  throughput %.0f req/s   (target >= 10000)\n",
                static_cast<double>(all.size()) / elapsed);
    std::printf(
        "  latency    p50 %.3f ms   p90 %.3f ms   p99 %.3f ms   max %.3f ms   (p99 target <= 10 "
        "ms)\n",
        percentile(all, 0.50), percentile(all, 0.90), percentile(all, 0.99),
        all.empty() ? 0.0 : all.back());
    status = errors == 0 ? 0 : 1;
  }
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
  return status;
}
