// MapBuilder throughput (input points/s through deskew, Table IV scan filters, intermediary
// maps and the final map), metrics points/s (Eqs. (23)-(26)), and peak RSS of a long vs a
// short stream over the same structure (targets: >= 2 M points/s, >= 1 M points/s, <= 1.5x).
// Synthetic VLP-16 sweeps (16 rings x 1800 azimuths, 10 Hz, per-point times) of a vessel
// circling two bridge piers under a deck beside a quay wall, with 0.5 % rain-like outliers.
// Run build-*/tests/bench/bench_map [laps_long=4].
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "worker/mapping/map_builder.h"
#include "worker/mapping/map_metrics.h"

namespace {

using keel::PointCloud;
using keel::Pose3;
using keel::TimeNs;
using namespace keel::mapping;

constexpr double kCircleRadius = 25.0;  // m, around the piers
constexpr double kLapS = 32.0;          // s: ~4.9 m/s, a whole number of 10 Hz sweeps per lap

// Periodic per lap (roll included), so every lap rescans the same structure from the same
// poses: a longer mission adds range noise and outliers, not new surfaces.
Pose3 vessel_pose(double t) {
  const double a = 2.0 * M_PI * t / kLapS;
  return keel::make_pose(
      Eigen::Quaterniond(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(0.02 * std::sin(10.0 * a), Eigen::Vector3d::UnitX())),
      Eigen::Vector3d(kCircleRadius * std::cos(a), kCircleRadius * std::sin(a), 0.0));
}

struct Box {
  Eigen::Vector3d lo, hi;
};
const std::vector<Box>& scene() {
  static const std::vector<Box> boxes{
      {{-8, -3, -5}, {-4, 3, 8}},     // pier 1
      {{4, -3, -5}, {8, 3, 8}},       // pier 2
      {{-60, -4, 8}, {60, 4, 9.5}},   // deck
      {{-60, 40, -5}, {60, 42, 6}},   // quay wall
      {{-60, -60, -6}, {60, 60, -5}}  // river bed (seen near the vessel only)
  };
  return boxes;
}

// Slab method; returns the entry distance or +inf.
double ray_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& b) {
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double inv = 1.0 / d[a];
    double near = (b.lo[a] - o[a]) * inv, far = (b.hi[a] - o[a]) * inv;
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0;
}

PointCloud simulate_sweep(double t_scan, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, 0.01);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud scan;
  scan.t_ns = std::llround(t_scan * 1e9);
  scan.reserve(28800);
  const Pose3 T_body_lidar = keel::make_pose(Eigen::Quaterniond::Identity(), {0.0, 0.0, 1.0});
  for (int column = 0; column < 1800; ++column) {
    const double dt = 0.1 * column / 1800.0;
    const Pose3 T_world_lidar = vessel_pose(t_scan + dt) * T_body_lidar;
    const double azimuth = 2.0 * M_PI * column / 1800.0;
    for (int ring = 0; ring < 16; ++ring) {
      const double elevation = (-15.0 + 2.0 * ring) * M_PI / 180.0;
      const Eigen::Vector3d dir(std::cos(elevation) * std::cos(azimuth),
                                std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      const Eigen::Vector3d d_world = T_world_lidar.linear() * dir;
      double range = std::numeric_limits<double>::infinity();
      for (const Box& box : scene()) {
        range = std::min(range, ray_box(T_world_lidar.translation(), d_world, box));
      }
      if (u(rng) < 0.005) range = 1.0 + 30.0 * u(rng);  // rain-like outlier
      if (!(range < 100.0)) continue;
      scan.xyz.push_back(((range + noise(rng)) * dir).cast<float>());
      scan.time_s.push_back(static_cast<float>(dt));
      scan.intensity.push_back(static_cast<float>(ring));
    }
  }
  return scan;
}

TransformTree make_tree(double duration_s) {
  keel::Trajectory poses;
  for (double t = 0.0; t <= duration_s + 0.2; t += 0.01) {
    poses.push_back({std::llround(t * 1e9), vessel_pose(t)});
  }
  TransformTree tree(poses);
  tree.set_extrinsic("lidar_h", keel::make_pose(Eigen::Quaterniond::Identity(), {0.0, 0.0, 1.0}));
  return tree;
}

MapBuilderOptions inspection_options(bool with_map_filters, double final_leaf_m = 0.05) {
  MapBuilderOptions options;  // Table IV lidar scan filters by default
  options.scans_per_intermediary = 10;
  if (with_map_filters) {
    options.default_sensor.intermediary_filters.filters.push_back(RadiusOutlierFilter{0.15, 2});
    options.default_sensor.final_filters.filters.push_back(VoxelGridFilter{final_leaf_m});
  }
  return options;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// CPU seconds of this process (all threads): on a shared machine wall time includes waiting
// for a core; CPU time / 2 is what the run would take with 2 idle cores.
double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

void throughput(const char* label, bool with_map_filters, int scans, PointCloud* map_out) {
  const TransformTree tree = make_tree(scans * 0.1);
  std::mt19937 rng(1);
  std::vector<PointCloud> sweeps;
  size_t points = 0;
  for (int s = 0; s < scans; ++s) {
    sweeps.push_back(simulate_sweep(0.1 * s, rng));
    points += sweeps.back().size();
  }
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = cpu_seconds();
  MapBuilder builder(tree, inspection_options(with_map_filters));
  for (PointCloud& sweep : sweeps) builder.add_scan("lidar_h", std::move(sweep));
  builder.finish();
  const double elapsed = seconds_since(start);
  const double cpu = cpu_seconds() - cpu_start;
  const SensorMapStats& stats = builder.stats("lidar_h");
  std::printf(
      "%-44s %9zu pts: wall %6.2f s = %5.2f M points/s; cpu %6.2f s = %5.2f M points/s "
      "per 2 cores -> %zu map points\n",
      label, points, elapsed, points / elapsed / 1e6, cpu, 2.0 * points / cpu / 1e6,
      stats.points_out);
  for (const FilterStep& step : stats.scan_stage.steps) {
    std::printf("    scan stage %-10s %10zu -> %10zu\n", step.filter.c_str(), step.points_in,
                step.points_out);
  }
  if (map_out != nullptr) *map_out = builder.sensor_map("lidar_h");
}

// --- metrics section (owned by the metrics engineer) ---------------------------------------
// Metrics throughput (Eqs. (23)-(26), r = 0.25 m, 2 threads) against the target of >= 1 M
// points/s. "query points/s" counts the points whose three metrics were computed; every query
// uses all its neighbours from the whole map. Neighbours per point = mean density * pi r^2.
void metrics_run(const char* label, const PointCloud& map, size_t max_query_points) {
  MapMetricsOptions options;  // r = 0.25 m, 2 threads
  options.max_query_points = max_query_points;
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = cpu_seconds();
  const MapMetrics metrics = compute_map_metrics(map, options);
  const double elapsed = seconds_since(start);
  const double cpu = cpu_seconds() - cpu_start;
  const double neighbours =
      metrics.surface_density.mean * M_PI * options.radius_m * options.radius_m;
  const double per_2_cores = 2.0 * metrics.query_points / cpu / 1e6;
  std::printf(
      "%-44s %9zu query pts of %9zu map pts (%.0f neighbours/pt): wall %6.2f s = %5.2f M query "
      "points/s; cpu %6.2f s = %5.2f M query points/s per 2 cores (target >= 1: %s)\n",
      label, metrics.query_points, metrics.points, neighbours, elapsed,
      metrics.query_points / elapsed / 1e6, cpu, per_2_cores,
      per_2_cores >= 1.0 ? "met" : "MISSED");
  std::printf("    density mean %.1f /m^2, roughness mean %.4f m, planarity mean %.3f\n",
              metrics.surface_density.mean, metrics.roughness.mean, metrics.planarity.mean);
}

void metrics_throughput(const PointCloud& map) {
  metrics_run("metrics (r = 0.25 m, 2 threads), 5 cm map", map, 0);
}

// A denser inspection map (final voxel 2 cm) built from the same sweeps; every 16th point queried.
void dense_metrics_throughput(int scans) {
  const TransformTree tree = make_tree(scans * 0.1);
  std::mt19937 rng(1);
  MapBuilder builder(tree, inspection_options(true, 0.02));
  for (int s = 0; s < scans; ++s) builder.add_scan("lidar_h", simulate_sweep(0.1 * s, rng));
  builder.finish();
  const PointCloud map = builder.sensor_map("lidar_h");
  metrics_run("metrics (r = 0.25 m, 2 threads), 2 cm map", map, map.size() / 16);
  metrics_run("metrics (r = 0.25 m, 2 threads), 2 cm map", map, 0);
}
// --- end of metrics section ----------------------------------------------------------------

// One stream of `laps` laps, scans generated on the fly and never stored; prints the peak RSS
// in MiB. Runs in its own process (see main) so each figure is that stream's alone.
int run_stream(double laps, double final_leaf_m) {
  const int scans = static_cast<int>(laps * kLapS / 0.1);
  const TransformTree tree = make_tree(scans * 0.1);
  MapBuilder builder(tree, inspection_options(true, final_leaf_m));
  std::mt19937 rng(2);
  for (int s = 0; s < scans; ++s) builder.add_scan("lidar_h", simulate_sweep(0.1 * s, rng));
  builder.finish();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("%.1f %zu\n", usage.ru_maxrss / 1024.0, builder.stats("lidar_h").points_out);
  return 0;
}

// Runs `bench_map --stream laps` as a fresh process (a forked child would start with this
// process's pages counted in its RSS) and reads its peak RSS.
double stream_peak_rss_mib(double laps, double final_leaf_m, size_t* map_points) {
  const std::string command = "/proc/" + std::to_string(getpid()) + "/exe --stream " +
                              std::to_string(laps) + " " + std::to_string(final_leaf_m);
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return -1.0;
  double mib = -1.0;
  if (std::fscanf(pipe, "%lf %zu", &mib, map_points) != 2) mib = -1.0;
  pclose(pipe);
  return mib;
}

void memory_scaling(double laps_long, double final_leaf_m) {
  size_t short_points = 0, long_points = 0;
  const double short_mib = stream_peak_rss_mib(1.0, final_leaf_m, &short_points);
  const double long_mib = stream_peak_rss_mib(laps_long, final_leaf_m, &long_points);
  std::printf(
      "peak RSS, final voxel %.2f m: 1 lap (%.0f s) %.1f MiB, %zu map points; %.1f laps "
      "%.1f MiB, %zu map points: RSS ratio %.2f (target <= 1.5), map ratio %.2f, "
      "%.0f / %.0f bytes per map point\n",
      final_leaf_m, kLapS, short_mib, short_points, laps_long, long_mib, long_points,
      long_mib / short_mib, static_cast<double>(long_points) / short_points,
      short_mib * 1048576.0 / short_points, long_mib * 1048576.0 / long_points);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::string(argv[1]) == "--stream") {
    return run_stream(std::atof(argv[2]), std::atof(argv[3]));
  }
  if (argc == 2 && std::string(argv[1]) == "--metrics-only") {
    PointCloud map;
    throughput("MapBuilder, + intermediary ROR, final voxel", true, 100, &map);
    metrics_throughput(map);
    dense_metrics_throughput(100);
    return 0;
  }
  if (argc == 2 && std::string(argv[1]) == "--pipeline-only") {
    throughput("MapBuilder, + intermediary ROR, final voxel", true, 100, nullptr);
    return 0;
  }
  const double laps_long = argc > 1 ? std::atof(argv[1]) : 4.0;
  PointCloud map;
  throughput("MapBuilder, Table IV scan filters", false, 100, nullptr);
  throughput("MapBuilder, + intermediary ROR, final voxel", true, 100, &map);
  metrics_throughput(map);
  dense_metrics_throughput(100);
  memory_scaling(laps_long, 0.05);
  memory_scaling(laps_long, 0.10);
  return 0;
}
