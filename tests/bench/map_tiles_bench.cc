// Issue 17: a synthetic map of N points (default 100 M) through the map stage's out-of-core path
// within a memory budget (default 1 GiB, target: the whole run within it): what leaves the
// scans goes into spilled tiles (TiledMaps, the stage's budget shares), the final voxel grid
// runs tile by tile, and the outputs are made from the tiles as the stage makes them: the PLY
// file, the LOD tileset and the Table V metrics (a single Draco file does not fit the budget and
// is not made, as in the stage).
//
// The map: a bridge deck (400 m x 80 m) and two 10 m walls sampled on the 2 cm voxel lattice,
// one point per voxel (jittered inside it), fed in 1 m strips along the deck as a survey
// would, so the map keeps every point: N points in, N out.
//
// Run: bench_map_tiles [--points N] [--budget-mb M] [--threads T] [--dir DIR] [--keep]
// Prints the peak RSS (VmHWM) after each phase against the budget, bytes spilled, tiles and
// seconds; the load average says how busy the machine was.
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "worker/mapping/filter_chain.h"
#include "worker/stages/map/tiled_maps.h"
#include "worker/stages/map/tiled_outputs.h"

namespace {

namespace fs = std::filesystem;
using keel::PointCloud;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double peak_rss_mib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0.0;
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

constexpr double kLeaf = 0.02;

// One strip [x0, x0 + 1 m) of the structure: deck at z = 10 m over y in [0, 80), walls at y = 0
// and y = 80 over z in [0, 10); one point per 2 cm voxel, jittered inside it.
void strip(int strip_index, double deck_width_m, std::mt19937& rng, PointCloud& out) {
  std::uniform_real_distribution<float> jitter(-0.45f, 0.45f), intensity(0.f, 255.f);
  const int per_metre = static_cast<int>(std::lround(1.0 / kLeaf));
  const auto at = [&](long i) { return static_cast<float>((i + 0.5 + jitter(rng)) * kLeaf); };
  const long x0 = static_cast<long>(strip_index) * per_metre;
  const long deck_cells = std::lround(deck_width_m / kLeaf);
  const long z_deck = std::lround(10.0 / kLeaf), wall_cells = std::lround(10.0 / kLeaf);
  for (long i = x0; i < x0 + per_metre; ++i) {
    for (long j = 0; j < deck_cells; ++j) {
      out.xyz.emplace_back(at(i), at(j), at(z_deck));
      out.intensity.push_back(intensity(rng));
    }
    for (const long j : {-1L, deck_cells})
      for (long k = 0; k < wall_cells; ++k) {
        out.xyz.emplace_back(at(i), at(j), at(k));
        out.intensity.push_back(intensity(rng));
      }
  }
}

}  // namespace

int main(int argc, char** argv) {
  double points = 100e6, budget_mb = 1024;
  int threads = 2;
  bool keep = false;
  fs::path dir = fs::temp_directory_path() / ("keel_bench_map_tiles_" + std::to_string(getpid()));
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--points" && i + 1 < argc) points = std::stod(argv[++i]);
    if (a == "--budget-mb" && i + 1 < argc) budget_mb = std::stod(argv[++i]);
    if (a == "--threads" && i + 1 < argc) threads = std::stoi(argv[++i]);
    if (a == "--dir" && i + 1 < argc) dir = argv[++i];
    if (a == "--keep") keep = true;
  }
  fs::create_directories(dir);
  // Per metre of deck: 80 m x 50 columns x 50 + 2 walls x 10 m x 50 x 50.
  const double deck_width = 80.0;
  const double per_strip = deck_width / kLeaf / kLeaf + 2 * 10.0 / kLeaf / kLeaf;
  const int strips = static_cast<int>(std::ceil(points / per_strip));
  std::printf(
      "synthetic map: %d strips of %.0f points (%.1f M), budget %.0f MiB, %d threads, "
      "load %s\n",
      strips, per_strip, strips * per_strip / 1e6, budget_mb, threads, load_average().c_str());
  try {
    const double budget = budget_mb * (1 << 20);
    keel::pipeline::TiledMaps maps(
        dir,
        {{"lidar", keel::mapping::filter_chain_from_json(
                       nlohmann::json::parse(R"([{"type": "voxel_grid", "leaf": 0.02}])"), "c")}},
        keel::pipeline::tiled_maps_options_for_budget(budget, threads, 0.25));
    auto start = std::chrono::steady_clock::now();
    std::mt19937 rng(1);
    size_t fed = 0;
    for (int s = 0; s < strips; ++s) {
      PointCloud batch;
      strip(s, deck_width, rng, batch);
      fed += batch.size();
      maps.add_final_input("lidar", batch);
    }
    std::printf("feed: %.1f M points in %.1f s; peak RSS %.0f MiB; spilled %.0f MiB\n", fed / 1e6,
                seconds_since(start), peak_rss_mib(), maps.store().bytes_spilled() / 1048576.0);
    start = std::chrono::steady_clock::now();
    maps.filter_sensor("lidar", {});
    const auto& stats = maps.filter_stats("lidar");
    std::printf(
        "filter: %zu tiles (%zu splits, largest %zu points) -> %.1f M points in %.1f s; peak RSS "
        "%.0f MiB\n",
        stats.tiles, stats.splits, stats.largest_tile_points, maps.points("lidar") / 1e6,
        seconds_since(start), peak_rss_mib());
    start = std::chrono::steady_clock::now();
    const auto tiles = maps.output_partition({"lidar"});
    keel::pipeline::write_tiled_ply(maps, {"lidar"}, tiles, dir / "map_lidar.ply");
    std::printf("ply: %.0f MB in %.1f s; peak RSS %.0f MiB\n",
                fs::file_size(dir / "map_lidar.ply") / 1e6, seconds_since(start), peak_rss_mib());
    start = std::chrono::steady_clock::now();
    keel::mapping::LodOptions lod;
    lod.max_points_per_tile = 100000;
    const auto tileset = keel::pipeline::write_tiled_tileset(maps, {"lidar"}, tiles, "lidar",
                                                             dir / "tiles_lidar.tar", lod);
    std::printf(
        "tiles: %zu LOD tiles, %.1f M finest points, %.0f MB in %.1f s; peak RSS %.0f MiB\n",
        tileset.tiles, tileset.points / 1e6, tileset.bytes / 1e6, seconds_since(start),
        peak_rss_mib());
    start = std::chrono::steady_clock::now();
    keel::mapping::MapMetricsOptions metrics_options;
    metrics_options.max_query_points = 20000;
    metrics_options.threads = threads;
    const auto metrics = keel::pipeline::tiled_map_metrics(maps, {"lidar"}, tiles, metrics_options);
    std::printf("metrics: %zu queries, density %.0f /m^2 in %.1f s; peak RSS %.0f MiB\n",
                metrics.query_points, metrics.surface_density.mean, seconds_since(start),
                peak_rss_mib());
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const bool every_point = tileset.points == fed && maps.points("lidar") == fed;
    std::printf(
        "peak RSS %.0f MiB with a %.0f MiB budget (%s); spilled %.0f MiB (spill buffers at most "
        "%.0f MiB); every point kept: %s; load now %s\n",
        peak_rss_mib(), budget_mb, peak_rss_mib() <= budget_mb ? "within" : "OVER",
        maps.store().bytes_spilled() / 1048576.0, maps.store().peak_bytes_buffered() / 1048576.0,
        every_point ? "yes" : "NO", load_average().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_map_tiles: %s\n", e.what());
    if (!keep) fs::remove_all(dir);
    return 1;
  }
  if (!keep) fs::remove_all(dir);
  return 0;
}
