// Stage `map` on keel-sim usv-bridge (seed 000 Sec. VI): the inspection map against the SLAM
// map (Table V: density x95, roughness -29 %, planarity +40 %; target: better on all three),
// input points/s of the whole stage (target >= 2 M/s on 2 cores), metrics points/s (>= 1 M/s)
// and the peak RSS of ~30-minute vs 5-minute surveys of the same bridge (issue 17: <= 1.2x with
// the default map.memory_budget_mb, the maps keeping every point): one lap at 1/6 the speed,
// and six laps at the same speed (memory_scaling).
//
// Each stage run is a fresh process (`bench_map_sim --stage MISSION WORK`), so its peak RSS is
// its own. On a shared machine wall time includes waiting for a core: CPU seconds are printed
// too, and "per 2 cores" = 2 x points / CPU seconds.
// Run build-*/tests/bench/bench_map_sim [--keep] [--skip-rss | --rss-only] [--skip-metrics-file]
// [--dir DIR] [--merge-leaves X] [--points-per-ring N] (--points-per-ring: the memory runs'
// lidar columns, default the simulator's 1875; --skip-metrics-file: no whole-map metrics run on
// map_lidar_h.ply; --merge-leaves: map.final_voxel_merge_radius_leaves of every run, 0 = plain
// voxel grid, default: the stage's default; --leaves 0.02,0.05: the final leaves of the memory
// runs, default both; --no-laps: no six-lap survey; --budget-mb N: map.memory_budget_mb of every
// run, default the stage's).
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/tum.h"
#include "worker/mapping/map_metrics.h"
#include "worker/stages/map/stage.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// map.final_voxel_merge_radius_leaves of every stage run (negative: the stage's default).
double g_merge_leaves = -1.0;
// map.memory_budget_mb of every stage run (0: the stage's default).
int g_budget_mb = 0;
std::vector<double> g_leaves = {0.02, 0.05};
bool g_laps = true;

json with_merge_option(json options) {
  if (g_merge_leaves >= 0.0) options["final_voxel_merge_radius_leaves"] = g_merge_leaves;
  if (g_budget_mb > 0) options["memory_budget_mb"] = g_budget_mb;
  return options;
}

double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Child mode: runs the stage, prints one JSON line {wall_s, cpu_s, peak_rss_mib, report}.
int run_stage_child(const fs::path& mission, const fs::path& work, const std::string& options) {
  fs::create_directories(work);
  keel::pipeline::StageContext context;
  context.mission_dir = mission;
  context.work_dir = work;
  context.options = options.empty() ? json::object() : json::parse(options);
  // The stage's log (per-task timings of the outputs phase) on stderr; stdout is the result.
  context.log = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = cpu_seconds();
  const auto result = keel::pipeline::make_map_stage()->run(context);
  const double wall = seconds_since(start), cpu = cpu_seconds() - cpu_start;
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const json out = {{"wall_s", wall},
                    {"cpu_s", cpu},
                    {"peak_rss_mib", usage.ru_maxrss / 1024.0},
                    {"report", result.report}};
  std::printf("%s\n", out.dump().c_str());
  return 0;
}

json stage_in_child(const fs::path& mission, const fs::path& work, const json& options) {
  const std::string command = "/proc/" + std::to_string(getpid()) + "/exe --stage '" +
                              mission.string() + "' '" + work.string() + "' '" + options.dump() +
                              "'";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) throw std::runtime_error("cannot start " + command);
  std::string text;
  char buffer[65536];
  while (size_t n = fread(buffer, 1, sizeof(buffer), pipe)) text.append(buffer, n);
  if (pclose(pipe) != 0) throw std::runtime_error("stage child failed: " + command);
  return json::parse(text);
}

// Path length of usv-bridge (so a mission of T seconds surveys the whole bridge once).
double bridge_path_length_m() {
  const keel::sim::Scenario s = keel::sim::make_scenario("usv-bridge", 1);
  keel::sim::MotionOptions m;
  return (s.motion->end_time() - m.start_rest_s - m.ramp_s) * m.cruise_speed_mps;
}

double simulate(const fs::path& dir, double duration_s, const std::vector<std::string>& sensors,
                const std::vector<std::string>& settings) {
  if (fs::exists(dir / "mission.yaml")) return 0.0;
  keel::sim::SimOptions o;
  o.scenario = "usv-bridge";
  o.seed = 1;
  o.out_dir = dir.string();
  o.duration_s = duration_s;
  o.sensors = sensors;
  o.settings = settings;
  const auto start = std::chrono::steady_clock::now();
  const auto summary = keel::sim::run_simulation(o);
  const double seconds = seconds_since(start);
  std::printf("simulated %s: %.0f s, %.0f m, %zu scans, %zu points in %.1f s\n",
              dir.filename().c_str(), summary.duration_s, summary.path_length_m, summary.scans,
              summary.scan_points, seconds);
  return seconds;
}

void print_distribution_row(const char* label, const json& maps, const char* metric,
                            const std::vector<std::string>& columns) {
  std::printf("  %-16s", label);
  for (const auto& c : columns) std::printf(" %14.5g", maps[c][metric]["mean"].get<double>());
  std::printf("   (median");
  for (const auto& c : columns) std::printf(" %.4g", maps[c][metric]["median"].get<double>());
  std::printf("; p05-p95");
  for (const auto& c : columns)
    std::printf(" [%.3g, %.3g]", maps[c][metric]["p05"].get<double>(),
                maps[c][metric]["p95"].get<double>());
  std::printf(")\n");
}

void print_table_v(const json& report) {
  const json& metrics = report["metrics"];
  const json& table = metrics["table_v"];
  std::vector<std::string> columns;
  for (const auto& c : table["columns"]) columns.push_back(c.get<std::string>());
  std::printf("Table V (r = %.2f m, means over <= %zu query points per map):\n  %-16s",
              metrics["radius_m"].get<double>(), metrics["max_query_points"].get<size_t>(), "");
  for (const auto& c : columns) std::printf(" %14s", c.c_str());
  std::printf("\n");
  print_distribution_row("density /m^2", metrics["maps"], "surface_density_per_m2", columns);
  print_distribution_row("roughness m", metrics["maps"], "roughness_m", columns);
  print_distribution_row("planarity", metrics["maps"], "planarity", columns);
  std::printf("  points        ");
  for (const auto& c : columns) std::printf(" %14zu", metrics["maps"][c]["points"].get<size_t>());
  std::printf("\n");
  const json& r = table["ratios"];
  const json& paper = r["paper_table_v"];
  std::printf(
      "  %s vs slam_map: density x%.1f (paper x%.1f), roughness %+.1f %% (paper %+.1f %%), "
      "planarity %+.1f %% (paper %+.1f %%)\n",
      table["inspection_map"].get<std::string>().c_str(), r["density_factor"].get<double>(),
      paper["density_factor"].get<double>(), r["roughness_change_percent"].get<double>(),
      paper["roughness_change_percent"].get<double>(), r["planarity_change_percent"].get<double>(),
      paper["planarity_change_percent"].get<double>());
  const json& beats = table["inspection_beats_slam"];
  std::printf("  inspection beats SLAM: density %s, roughness %s, planarity %s (target: all)\n",
              beats["surface_density"].get<bool>() ? "yes" : "NO",
              beats["roughness"].get<bool>() ? "yes" : "NO",
              beats["planarity"].get<bool>() ? "yes" : "NO");
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

void print_stage_figures(const json& run) {
  const json& report = run["report"];
  const json& timing = report["timing"];
  std::printf("load average now %s (2 cores; wall times include waiting for a core)\n",
              load_average().c_str());
  const double points = timing["input_points"].get<double>();
  const double wall = run["wall_s"].get<double>(), cpu = run["cpu_s"].get<double>();
  std::printf(
      "stage: %.0f input points; whole stage wall %.1f s = %.2f M points/s, cpu %.1f s = %.2f M "
      "points/s per 2 cores (target >= 2); scan phase %.1f s = %.2f M points/s; peak RSS %.0f "
      "MiB\n",
      points, wall, points / wall / 1e6, cpu, 2.0 * points / cpu / 1e6,
      timing["scans_seconds"].get<double>(), timing["input_points_per_second"].get<double>() / 1e6,
      run["peak_rss_mib"].get<double>());
  for (const auto& [sensor, entry] : report["sensors"].items()) {
    if (entry["stats"].is_null()) continue;
    const json& s = entry["stats"];
    std::printf("  %-8s %6zu scans (%zu outside), %10zu points in -> %9zu out", sensor.c_str(),
                s["scans"].get<size_t>(), s["scans_outside_trajectory"].get<size_t>(),
                s["points_in"].get<size_t>(), s["points_out"].get<size_t>());
    if (entry.contains("map") && entry["map"]["draco"].contains("bytes"))
      std::printf("; draco %.1f MB (%.2f B/pt), max error %.3f mm",
                  entry["map"]["draco"]["bytes"].get<double>() / 1e6,
                  entry["map"]["draco"]["bytes_per_point"].get<double>(),
                  entry["map"]["draco"]["max_position_error_m"].get<double>() * 1e3);
    else if (entry.contains("map"))
      std::printf("; no draco file (over the budget)");
    if (entry.contains("map") && entry["map"].contains("tiles"))
      std::printf("; %zu LOD tiles, %.1f MB", entry["map"]["tiles"]["tiles"].get<size_t>(),
                  entry["map"]["tiles"]["bytes"].get<double>() / 1e6);
    if (entry.contains("tiles"))
      std::printf("; %zu filter tiles (%zu splits, largest %zu points)",
                  entry["tiles"]["filter_tiles"].get<size_t>(),
                  entry["tiles"]["splits"].get<size_t>(),
                  entry["tiles"]["largest_tile_points"].get<size_t>());
    std::printf("\n");
    for (const char* stage : {"scan_stage", "intermediary_stage", "final_stage"})
      for (const auto& f : s[stage]["filters"])
        std::printf("      %-18s %-10s %10zu -> %10zu\n", stage,
                    f["filter"].get<std::string>().c_str(), f["points_in"].get<size_t>(),
                    f["points_out"].get<size_t>());
  }
  const json& combined = report["combined"];
  if (combined["draco"].contains("bytes"))
    std::printf(
        "  combined %zu points; draco %.1f MB, max error %.3f mm (bound %.3f mm, range %.1f m)\n",
        combined["points"].get<size_t>(), combined["draco"]["bytes"].get<double>() / 1e6,
        combined["draco"]["max_position_error_m"].get<double>() * 1e3,
        combined["draco"]["position_error_bound_m"].get<double>() * 1e3,
        combined["draco"]["position_range_m"].get<double>());
  else
    std::printf("  combined %zu points; no draco file: %s\n", combined["points"].get<size_t>(),
                combined["draco"]["reason"].get<std::string>().c_str());
  if (combined.contains("tiles"))
    std::printf("  combined LOD tiles: %zu tiles, %.1f MB, %.1f s\n",
                combined["tiles"]["tiles"].get<size_t>(),
                combined["tiles"]["bytes"].get<double>() / 1e6,
                combined["tiles"]["seconds"].get<double>());
  if (report.contains("memory")) {
    const json& m = report["memory"];
    std::printf(
        "  memory: budget %d MiB, stage peak RSS %.0f MiB (process %.0f MiB), spilled %.0f MiB "
        "(spill buffers at most %.0f of %.0f MiB)\n",
        m["budget_mb"].get<int>(), m["peak_rss_mib"].get<double>(),
        run["peak_rss_mib"].get<double>(), m["bytes_spilled"].get<double>() / (1 << 20),
        m["spill_buffered_peak_mib"].get<double>(), m["spill_buffer_budget_mib"].get<double>());
  }
  if (timing.contains("outputs_and_metrics_seconds"))
    std::printf("  outputs and metrics (after the scans): %.1f s wall\n",
                timing["outputs_and_metrics_seconds"].get<double>());
  std::printf("  metrics in the stage: %.1f s, %.2f M query points/s\n",
              timing["metrics_seconds"].get<double>(),
              timing["metrics_query_points_per_second"].get<double>() / 1e6);
}

// Metrics on the whole lidar_h inspection map (every point a query point).
void metrics_throughput(const fs::path& ply) {
  const keel::PointCloud map = keel::io::read_scan_file(ply, 0);
  keel::mapping::MapMetricsOptions options;  // r = 0.25 m, 2 threads, every point
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = cpu_seconds();
  const auto metrics = keel::mapping::compute_map_metrics(map, options);
  const double wall = seconds_since(start), cpu = cpu_seconds() - cpu_start;
  std::printf(
      "metrics on %s (every point, r = 0.25 m): %zu points, wall %.1f s = %.2f M points/s, cpu "
      "%.1f s = %.2f M points/s per 2 cores (target >= 1); mean neighbours %.0f\n",
      ply.filename().c_str(), metrics.query_points, wall, metrics.query_points / wall / 1e6, cpu,
      2.0 * metrics.query_points / cpu / 1e6, metrics.surface_density.mean * M_PI * 0.0625);
}

// Map options for a lidar of `points_per_ring` columns (0: the simulator's VLP-16 default,
// whose 0.19 deg matches Table IV's DROR alpha of 0.2 deg, so the defaults apply). A reduced
// lidar gets Table IV's scan filters with DROR's alpha set to its horizontal resolution
// (360 deg / points): with 0.2 deg, DROR would remove nearly every point of a sparser ring.
json lidar_options(double final_leaf_m, int points_per_ring) {
  json options = {{"final_voxel_leaf_m", final_leaf_m}};
  if (points_per_ring == 0) return options;
  json filters = json::parse(R"([
      {"type": "crop_box", "min": [-60, -60, -60], "max": [60, 60, 60], "remove": "outside"},
      {"type": "crop_box", "min": [-2, -2, -2], "max": [2, 2, 2], "remove": "inside"},
      {"type": "dror", "beta": 3.0, "alpha_deg": 0.2, "k_min": 4, "sr_min": 0.01}])");
  filters[2]["alpha_deg"] = 360.0 / points_per_ring;
  options["lidar_filters"] = {{"scan_filters", filters}};
  return options;
}

// Where a longer survey's map grows: each sensor's map points of the two runs binned by their
// distance from the vessel's path (the mission's map poses, one per metre travelled), counted
// on every 50th map point.
void print_growth_by_range(const fs::path& mission, const fs::path& short_work,
                           const fs::path& long_work, const std::vector<std::string>& sensors) {
  std::vector<Eigen::Vector3f> path;
  for (const auto& pose : keel::io::read_tum(mission / "map_poses.tum")) {
    const Eigen::Vector3f p = pose.T_world_body.translation().cast<float>();
    if (path.empty() || (p - path.back()).norm() >= 1.0f) path.push_back(p);
  }
  const std::vector<double> edges = {0, 5, 10, 20, 30, 60, 1e9};
  const auto histogram = [&](const fs::path& ply) {
    const keel::PointCloud map = keel::io::read_scan_file(ply, 0);
    std::vector<size_t> counts(edges.size() - 1, 0);
    for (size_t n = 0; n < map.size(); n += 50) {
      float d2 = std::numeric_limits<float>::max();
      for (const auto& p : path) d2 = std::min(d2, (map.xyz[n] - p).squaredNorm());
      const double d = std::sqrt(d2);
      for (size_t b = 0; b + 1 < edges.size(); ++b)
        if (d < edges[b + 1]) {
          ++counts[b];
          break;
        }
    }
    return counts;
  };
  for (const auto& sensor : sensors) {
    const auto a = histogram(short_work / keel::pipeline::map_ply_file(sensor));
    const auto b = histogram(long_work / keel::pipeline::map_ply_file(sensor));
    std::printf("  %-8s map growth by distance from the path:", sensor.c_str());
    for (size_t k = 0; k < a.size(); ++k) {
      const std::string bin = k + 2 == edges.size() ? ">" + std::to_string(int(edges[k]))
                                                    : std::to_string(int(edges[k])) + "-" +
                                                          std::to_string(int(edges[k + 1]));
      std::printf(" %s m %.2fx (%zu)", bin.c_str(), a[k] ? double(b[k]) / double(a[k]) : 0.0, b[k]);
    }
    std::printf("\n");
  }
}

// One survey of the bridge for the memory runs: `laps` laps at `speed_mps`.
struct Survey {
  std::string name;  // mission folder bridge_<name>, stage work folders work_<name>_<leaf>
  double speed_mps = 0.0;
  int laps = 1;
  double duration_s = 0.0;
  std::string label() const {
    char text[96];
    std::snprintf(text, sizeof(text), "%.0f-min, %s at %.2f m/s", duration_s / 60.0,
                  laps == 1 ? "one lap" : (std::to_string(laps) + " laps").c_str(), speed_mps);
    return text;
  }
};

// The simulator's duration of `laps` laps of usv-bridge at `speed_mps` (ramps included).
double bridge_duration_s(double speed_mps, int laps) {
  keel::sim::ScenarioOptions options;
  options.motion.cruise_speed_mps = speed_mps;
  options.speed_overridden = true;
  options.motion.laps = laps;
  return keel::sim::make_scenario("usv-bridge", 1, options).default_duration_s;
}

void memory_scaling(const fs::path& root, bool keep, int points_per_ring) {
  // The same bridge surveyed three ways, with the simulator's VLP-16 (1875 points per ring;
  // ~4 GB on disk per 30-minute mission) unless `points_per_ring` reduces it (450 keeps a
  // 30-minute mission ~1 GB, but leaves even the 30-minute map far from saturating the
  // structure at a 2 cm leaf, so the ratio then mostly measures undersampling):
  //  - one lap in 5 minutes (the reference);
  //  - one lap in 30 minutes at 1/6 the speed: a longer mission that also samples the surfaces
  //    6x more densely along the path;
  //  - six laps in a row at the 5-minute speed (~32 minutes with the turn-arounds): a longer
  //    mission that repeats the same sampling, e.g. repeated inspection passes.
  const double length = bridge_path_length_m();
  const std::vector<std::string> sensors = {"lidar_h", "sonar"};
  const double fast_mps = length / (5 * 60.0 - 6.0), slow_mps = length / (30 * 60.0 - 6.0);
  std::vector<Survey> surveys = {{"5min", fast_mps, 1, 5 * 60.0},
                                 {"30min", slow_mps, 1, 30 * 60.0}};
  if (g_laps) surveys.push_back({"6laps", fast_mps, 6, bridge_duration_s(fast_mps, 6)});
  for (const Survey& survey : surveys) {
    std::vector<std::string> settings = {"motion.speed=" + std::to_string(survey.speed_mps)};
    if (survey.laps != 1) settings.push_back("motion.laps=" + std::to_string(survey.laps));
    if (points_per_ring > 0)
      settings.push_back("lidar.points_per_ring=" + std::to_string(points_per_ring));
    simulate(root / ("bridge_" + survey.name), survey.duration_s, sensors, settings);
  }
  for (const double leaf : g_leaves) {
    const auto work = [&](const Survey& survey) {
      return root / ("work_" + survey.name + "_" + std::to_string(leaf));
    };
    std::vector<json> runs;
    for (const Survey& survey : surveys) {
      runs.push_back(stage_in_child(root / ("bridge_" + survey.name), work(survey),
                                    with_merge_option(lidar_options(leaf, points_per_ring))));
      std::printf("%s, final voxel %.2f m: ", survey.label().c_str(), leaf);
      print_stage_figures(runs.back());
    }
    const double reference_mib = runs[0]["peak_rss_mib"].get<double>();
    for (size_t k = 1; k < surveys.size(); ++k) {
      std::printf("%s vs %s, final voxel %.2f m:\n", surveys[k].label().c_str(),
                  surveys[0].label().c_str(), leaf);
      print_growth_by_range(root / ("bridge_" + surveys[0].name), work(surveys[0]),
                            work(surveys[k]), sensors);
      const double mib = runs[k]["peak_rss_mib"].get<double>();
      std::printf(
          "peak RSS, final voxel %.2f m: %s %.0f MiB (%zu map points), %s %.0f MiB (%zu map "
          "points): ratio %.2f (target <= 1.2 with the default budget)\n",
          leaf, surveys[0].label().c_str(), reference_mib,
          runs[0]["report"]["combined"]["points"].get<size_t>(), surveys[k].label().c_str(), mib,
          runs[k]["report"]["combined"]["points"].get<size_t>(), mib / reference_mib);
    }
  }
  if (!keep)
    for (const Survey& survey : surveys) fs::remove_all(root / ("bridge_" + survey.name));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 4 && std::string(argv[1]) == "--stage")
    return run_stage_child(argv[2], argv[3], argc >= 5 ? argv[4] : "");
  bool keep = false, skip_rss = false, rss_only = false, skip_metrics_file = false;
  int points_per_ring = 0;
  fs::path root = fs::temp_directory_path() / ("keel_bench_map_sim_" + std::to_string(getpid()));
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--keep") keep = true;
    if (a == "--skip-rss") skip_rss = true;
    if (a == "--rss-only") rss_only = true;
    if (a == "--skip-metrics-file") skip_metrics_file = true;
    if (a == "--dir" && i + 1 < argc) root = argv[++i];
    if (a == "--merge-leaves" && i + 1 < argc) g_merge_leaves = std::stod(argv[++i]);
    if (a == "--points-per-ring" && i + 1 < argc) points_per_ring = std::stoi(argv[++i]);
    if (a == "--budget-mb" && i + 1 < argc) g_budget_mb = std::stoi(argv[++i]);
    if (a == "--no-laps") g_laps = false;
    if (a == "--leaves" && i + 1 < argc) {
      g_leaves.clear();
      std::string list = argv[++i];
      for (size_t at = 0; at <= list.size();) {
        const size_t comma = std::min(list.find(',', at), list.size());
        g_leaves.push_back(std::stod(list.substr(at, comma - at)));
        at = comma + 1;
      }
    }
  }
  fs::create_directories(root);
  try {
    if (rss_only) {
      memory_scaling(root, keep, points_per_ring);
      if (!keep) fs::remove_all(root);
      return 0;
    }
    // Full usv-bridge mission, the three range sensors of seed 000 Sec. VI.
    const fs::path mission = root / "bridge_full";
    simulate(mission, 0.0, {"lidar_h", "lidar_v", "sonar"}, {});
    const json run = stage_in_child(mission, root / "work_full", with_merge_option(json::object()));
    std::printf("usv-bridge 220 s, lidar_h + lidar_v + sonar, default map options, poses: %s\n",
                run["report"]["poses"]["source"].get<std::string>().c_str());
    print_stage_figures(run);
    print_table_v(run["report"]);
    if (!skip_metrics_file)
      metrics_throughput(root / "work_full" / keel::pipeline::map_ply_file("lidar_h"));
    if (!skip_rss) memory_scaling(root, keep, points_per_ring);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_map_sim: %s\n", e.what());
    if (!keep) fs::remove_all(root);
    return 1;
  }
  if (!keep) fs::remove_all(root);
  return 0;
}
