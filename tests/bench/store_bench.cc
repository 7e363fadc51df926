// get_job throughput of the SQLite store (GET /v1/jobs/{id} needs >= 10,000/s in total).
// Run: build/tests/bench/bench_store [--benchmark_filter=GetJob]
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "storage/store.h"

namespace {

namespace fs = std::filesystem;
using keel::storage::Store;

// One store shared by all benchmark threads: 1,000 jobs, half with two finished stages.
struct Fixture {
  fs::path dir;
  std::unique_ptr<Store> store;
  std::vector<std::string> job_ids;

  Fixture() {
    dir =
        fs::temp_directory_path() / ("keel-store-bench-" + std::to_string(std::random_device{}()));
    fs::create_directories(dir);
    store = keel::storage::open_sqlite_store(dir);
    keel::proto::MissionRequest mission{"bench", store->put_blob("bundle"), "", ""};
    const std::string mission_id = store->create_mission(mission).id;
    keel::proto::JobRequest request{mission_id, {"ingest", "refine", "map"}, {}};
    for (int i = 0; i < 1000; ++i) job_ids.push_back(store->create_job(request, "").id);
    for (int i = 0; i < 500; ++i) {
      auto lease = store->lease_job({"bench", 3600});
      store->complete_stage(lease->job.id, "ingest", {lease->lease_id, {{"frames", i}}, 1.0});
      store->complete_stage(lease->job.id, "refine", {lease->lease_id, {}, 2.0});
    }
  }
  ~Fixture() {
    store.reset();
    std::error_code ignored;
    fs::remove_all(dir, ignored);
  }
};

Fixture& fixture() {
  static Fixture instance;
  return instance;
}

void BM_GetJob(benchmark::State& state) {
  Fixture& f = fixture();
  size_t i = static_cast<size_t>(state.thread_index()) * 7919;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f.store->get_job(f.job_ids[i++ % f.job_ids.size()]));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_GetJob)->Threads(1)->Threads(2)->UseRealTime();

void BM_CheckToken(benchmark::State& state) {
  Fixture& f = fixture();
  if (state.thread_index() == 0) f.store->add_token("bench-token-0123456789abcdef", keel::storage::admin_token("bench"));
  for (auto _ : state)
    benchmark::DoNotOptimize(f.store->check_token("bench-token-0123456789abcdef"));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_CheckToken)->Threads(1)->Threads(2)->UseRealTime();

// Writes for scale: each heartbeat is one durable (fsynced) transaction.
void BM_Heartbeat(benchmark::State& state) {
  Fixture& f = fixture();
  auto lease = f.store->lease_job({"bench-hb", 3600});
  if (!lease) {
    state.SkipWithError("no queued job left to lease");
    return;
  }
  for (auto _ : state) f.store->heartbeat(lease->job.id, {lease->lease_id, "ingest", 0.5, {}});
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Heartbeat)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
