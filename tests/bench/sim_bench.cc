// keel-sim throughput: the usv-bridge mission (seed 000 Environment 1, 220 s) with every
// sensor, written into a temporary folder. Target: under 60 s on 2 cores.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "tests/sim/simulator.h"

namespace {

void BM_UsvBridgeAllSensors(benchmark::State& state) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("keel_bench_sim_" + std::to_string(::getpid()));
  keel::sim::SimSummary summary;
  for (auto _ : state) {
    keel::sim::SimOptions options;
    options.scenario = "usv-bridge";
    options.seed = 1;
    options.out_dir = dir.string();
    options.duration_s = static_cast<double>(state.range(0));
    options.threads = 2;
    summary = keel::sim::run_simulation(options);
    state.PauseTiming();
    fs::remove_all(dir);
    state.ResumeTiming();
  }
  state.counters["scans"] = static_cast<double>(summary.scans);
  state.counters["points"] = static_cast<double>(summary.scan_points);
  state.counters["images"] = static_cast<double>(summary.images);
  state.counters["points_per_s"] =
      benchmark::Counter(static_cast<double>(summary.scan_points), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_UsvBridgeAllSensors)->Arg(220)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
