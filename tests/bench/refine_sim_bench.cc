// The `refine` stage on keel-sim missions (IMU + DVL + depth; recorded MAP and odometry), seed
// 000 Table II style. Not a CTest test; run build/tests/bench/bench_refine_sim [seeds] [part]
// [refine options JSON] [keel-sim key=value ...]; seeds: N (1..N, default 20), A-B or a,b,c.
//   1. usv-bridge (220 s) and usv-corridor (its full path), every seed: translational ATE
//      (SE(3) Umeyama) of the MAP poses and of the refinement without and with DVL, whether
//      each refinement is worse than MAP, and the stage's self-check (keyframes that moved from
//      their MAP pose beyond its stated uncertainty); then mean, median and worst per mode.
//      Targets (issues 4 and 19): DVL fusion lowers the mean ATE by >= 40 % in both scenarios;
//      with DVL never worse than MAP; without DVL never worse than MAP on the bridge and at
//      most 10 % worse on the corridor;
//   2. the same missions with a 2 % DVL scale error (keel-sim --dvl-scale 1.02): ATE with s_d
//      estimated vs s_d held at the known 1.02 (target: within 10 %); seeds from
//      KEEL_REFINE_BENCH_SCALE_SEEDS (default: the seeds above);
//   3. the solve time of a 10-minute usv-bridge mission (speed lowered so the path takes
//      600 s; target <= 5 s on 2 cores).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"
#include "worker/stages/refine/stage.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kRoot =
    fs::temp_directory_path() / ("keel_bench_refine_" + std::to_string(::getpid()));

std::vector<std::string> g_sim_settings;  // fourth argument: keel-sim --set items

fs::path simulate(const std::string& scenario, uint64_t seed, double dvl_scale,
                  const std::vector<std::string>& settings = {}, double duration_s = 0.0) {
  const fs::path dir = kRoot / (scenario + "_" + std::to_string(seed) + "_" +
                                std::to_string(static_cast<int>(dvl_scale * 1000)));
  fs::remove_all(dir);
  keel::sim::SimOptions o;
  o.scenario = scenario;
  o.seed = seed;
  o.out_dir = dir.string();
  o.sensors = {"imu", "dvl", "depth"};
  o.dvl_scale = dvl_scale;
  o.settings = settings;
  o.settings.insert(o.settings.end(), g_sim_settings.begin(), g_sim_settings.end());
  o.duration_s = duration_s;
  keel::sim::run_simulation(o);
  return dir;
}

std::vector<std::string> g_targets;  // the summary: one line per figure and its target

void target(const std::string& scenario, const char* figure, double value, const char* unit,
            const char* target_text, bool met) {
  char line[256];
  std::snprintf(line, sizeof line, "  %-13s %-44s %8.3f%-2s  target %-22s %s", scenario.c_str(),
                figure, value, unit, target_text, met ? "met" : "MISSED");
  g_targets.push_back(line);
}

json g_extra_options = json::object();  // third argument: refine options for every run

json run_refine(const fs::path& mission, const json& options) {
  keel::pipeline::StageContext context;
  context.mission_dir = mission;
  context.work_dir = mission / "work";
  context.options = options;
  context.options.update(g_extra_options);
  fs::create_directories(context.work_dir);
  return keel::pipeline::make_refine_stage()->run(context).report;
}

double ate(const json& report, const char* row) {
  return report["evaluation"]["table"][row]["ate"]["translation_m"]["rmse"].get<double>();
}

struct Mean {
  double sum = 0.0;
  int n = 0;
  void add(double x) {
    sum += x;
    ++n;
  }
  double value() const { return n ? sum / n : 0.0; }
};

// Mean, median and worst (largest) of a column.
struct Column {
  std::vector<double> values;
  void add(double x) { values.push_back(x); }
  double mean() const {
    double sum = 0.0;
    for (double v : values) sum += v;
    return values.empty() ? 0.0 : sum / values.size();
  }
  double median() const {
    if (values.empty()) return 0.0;
    std::vector<double> v = values;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  }
  double worst() const {
    return values.empty() ? 0.0 : *std::max_element(values.begin(), values.end());
  }
};

std::vector<int> g_seeds;  // first argument

// "N" -> 1..N, "A-B" -> A..B, "a,b,c" -> those.
std::vector<int> parse_seeds(const std::string& text) {
  std::vector<int> out;
  const size_t dash = text.find('-');
  if (text.find(',') != std::string::npos) {
    size_t start = 0;
    while (start <= text.size()) {
      const size_t comma = std::min(text.find(',', start), text.size());
      out.push_back(std::stoi(text.substr(start, comma - start)));
      start = comma + 1;
    }
  } else if (dash != std::string::npos) {
    for (int s = std::stoi(text.substr(0, dash)); s <= std::stoi(text.substr(dash + 1)); ++s)
      out.push_back(s);
  } else {
    for (int s = 1; s <= std::stoi(text); ++s) out.push_back(s);
  }
  if (out.empty()) throw std::invalid_argument("seeds: none in '" + text + "'");
  return out;
}

void table_ii(const std::string& scenario) {
  // Without DVL the refinement may be worse than MAP by at most this factor (issue 19): on the
  // corridor the odometry's lost axis leaves only the MAP poses and the IMU along it.
  const double without_tolerance = scenario == "usv-corridor" ? 1.10 : 1.0;
  std::printf("\n%s: ATE rmse (m), SE(3) Umeyama, keyframes vs ground truth\n", scenario.c_str());
  std::printf("%6s %8s %9s %8s %9s %8s %9s %8s %11s %8s %8s\n", "seed", "MAP", "noDVL", "/MAP",
              "DVL", "/MAP", "DVL-gain", "flagged", "moved_rms", "s_d", "solve_s");
  Column map, without, with, without_ratio, with_ratio;
  int with_worse = 0, without_worse = 0;
  for (int seed : g_seeds) {
    const fs::path mission = simulate(scenario, seed, 1.0);
    const json r = run_refine(mission, json::object());
    const double a_map = ate(r, "map"), a_without = ate(r, "refined_without_dvl"),
                 a_with = ate(r, "refined_with_dvl");
    const bool w_worse = a_with > a_map, wo_worse = a_without > without_tolerance * a_map;
    with_worse += w_worse;
    without_worse += wo_worse;
    const json& check = r["self_check"];
    std::printf("%6d %8.4f %9.4f %7.2f%s %9.4f %7.2f%s %8.1f%% %4d/%-4d %10.4f %8.4f %8.2f\n", seed,
                a_map, a_without, a_without / a_map, wo_worse ? "!" : " ", a_with, a_with / a_map,
                w_worse ? "!" : " ", 100.0 * (1.0 - a_with / a_without),
                check["flagged_keyframes"].get<int>(), check["keyframes"].get<int>(),
                check["translation_m"]["rms"].get<double>(),
                r["dvl"]["dvl_scale"]["value"].get<double>(),
                r["solver"]["total_time_s"].get<double>());
    std::fflush(stdout);
    map.add(a_map);
    without.add(a_without);
    with.add(a_with);
    without_ratio.add(a_without / a_map);
    with_ratio.add(a_with / a_map);
    fs::remove_all(mission);
  }
  std::printf(
      "  (! = worse than MAP%s; flagged = keyframes the stage's self-check flags as moved\n"
      "   beyond their stated uncertainty; moved_rms = RMS translation from the MAP poses)\n",
      scenario == "usv-corridor" ? " by more than 10 % without DVL" : "");
  std::printf("%8s %10s %10s %10s %10s %10s\n", "", "MAP", "noDVL", "DVL", "noDVL/MAP", "DVL/MAP");
  std::printf("%8s %10.4f %10.4f %10.4f %10.3f %10.3f\n", "mean", map.mean(), without.mean(),
              with.mean(), without_ratio.mean(), with_ratio.mean());
  std::printf("%8s %10.4f %10.4f %10.4f %10.3f %10.3f\n", "median", map.median(), without.median(),
              with.median(), without_ratio.median(), with_ratio.median());
  std::printf("%8s %10.4f %10.4f %10.4f %10.3f %10.3f\n", "worst", map.worst(), without.worst(),
              with.worst(), without_ratio.worst(), with_ratio.worst());
  const double fusion = 100.0 * (1.0 - with.mean() / without.mean());
  target(scenario, "DVL fusion: mean ATE lower than without DVL by", fusion, " %", ">= 40 %",
         fusion >= 40.0);
  target(scenario, "seeds with DVL worse than MAP", with_worse, "", "0", with_worse == 0);
  target(scenario,
         scenario == "usv-corridor" ? "seeds without DVL > 1.10 x MAP"
                                    : "seeds without DVL worse than MAP",
         without_worse, "", "0", without_worse == 0);
  target(scenario, "worst ATE ratio with DVL / MAP", with_ratio.worst(), "", "<= 1",
         with_ratio.worst() <= 1.0);
  target(scenario, "worst ATE ratio without DVL / MAP", without_ratio.worst(), "",
         scenario == "usv-corridor" ? "<= 1.10" : "<= 1",
         without_ratio.worst() <= without_tolerance);
}

void scale_error(const std::string& scenario, const std::vector<int>& seeds) {
  std::printf("\n%s with a 2%% DVL scale error (s_d = 1.02): ATE rmse (m)\n", scenario.c_str());
  std::printf("%6s %12s %12s %10s %16s\n", "seed", "s_d estim.", "s_d fixed", "ratio",
              "s_d estimate");
  Mean est, fixed;
  for (int seed : seeds) {
    const fs::path mission = simulate(scenario, seed, 1.02);
    const json a = run_refine(mission, {{"compare_without_dvl", false}});
    const json b = run_refine(mission, {{"compare_without_dvl", false},
                                        {"estimate_dvl_scale", false},
                                        {"dvl_scale_initial", 1.02}});
    const double a_est = ate(a, "refined_with_dvl"), a_fixed = ate(b, "refined_with_dvl");
    std::printf("%6d %12.4f %12.4f %10.3f %9.4f+-%.4f\n", seed, a_est, a_fixed, a_est / a_fixed,
                a["dvl"]["dvl_scale"]["value"].get<double>(),
                a["dvl"]["dvl_scale"]["sigma"].get<double>());
    est.add(a_est);
    fixed.add(a_fixed);
    fs::remove_all(mission);
  }
  std::printf("%6s %12.4f %12.4f %10.3f   (mean; target: estimated within 10%% of fixed)\n", "mean",
              est.value(), fixed.value(), est.value() / fixed.value());
  const double ratio = est.value() / fixed.value();
  target(scenario, "2% scale error: mean ATE s_d estimated / known", ratio, "", "<= 1.10",
         ratio <= 1.10);
}

void ten_minutes() {
  const keel::sim::Scenario s = keel::sim::make_scenario("usv-bridge", 1);
  const keel::sim::MotionOptions m;
  const double speed = s.motion->path().length() / (600.0 - m.start_rest_s - m.ramp_s);
  const fs::path mission =
      simulate("usv-bridge", 1, 1.0, {"motion.speed=" + std::to_string(speed)});
  const auto t0 = std::chrono::steady_clock::now();
  const json r = run_refine(mission, {{"compare_without_dvl", false}});
  const double stage_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const json& solver = r["solver"];
  std::printf(
      "\n10-minute usv-bridge mission (%.0f s, speed %.2f m/s, %d keyframes, %d IMU / %d DVL "
      "factors):\n  solver total %.2f s (Ceres %.2f s, covariance %.2f s, %d iterations); whole "
      "stage incl. reading %.2f s (target: solve <= 5 s)\n  ATE rmse MAP %.4f m, refined %.4f m\n",
      r["inputs"]["keyframes"]["duration_s"].get<double>(), speed, solver["keyframes"].get<int>(),
      solver["factors"]["imu"].get<int>(), solver["factors"]["dvl"].get<int>(),
      solver["total_time_s"].get<double>(), solver["solve_time_s"].get<double>(),
      solver["covariance_time_s"].get<double>(), solver["iterations"].get<int>(), stage_s,
      ate(r, "map"), ate(r, "refined_with_dvl"));
  const double solve_s = solver["total_time_s"].get<double>();
  target("usv-bridge", "10-minute mission: solver total", solve_s, " s", "<= 5 s (2 cores)",
         solve_s <= 5.0);
  fs::remove_all(mission);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> scale_seeds;
  try {
    g_seeds = parse_seeds(argc > 1 ? argv[1] : "20");
    const char* env = std::getenv("KEEL_REFINE_BENCH_SCALE_SEEDS");
    scale_seeds = env ? parse_seeds(env) : g_seeds;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_refine_sim: seeds: expected N, A-B or a,b,c (%s)\n", e.what());
    return 1;
  }
  // Optional second argument: run only the parts whose name contains it, e.g. "scale" or
  // "fusion/usv-corridor" (parts: fusion/<scenario>, scale/<scenario>, ten_minutes).
  const std::string only = argc > 2 ? argv[2] : "";
  // Optional third argument: refine options (JSON) added to every run, e.g. '{"map_anchors":
  // false}', to compare variants on the same missions.
  if (argc > 3) g_extra_options = json::parse(argv[3]);
  // Further arguments: keel-sim settings (key=value) for every simulated mission.
  for (int k = 4; k < argc; ++k) g_sim_settings.push_back(argv[k]);
  auto wanted = [&](const std::string& part) {
    return only.empty() || part.find(only) != std::string::npos;
  };
  try {
    for (const char* scenario : {"usv-bridge", "usv-corridor"})
      if (wanted(std::string("fusion/") + scenario)) table_ii(scenario);
    for (const char* scenario : {"usv-bridge", "usv-corridor"})
      if (wanted(std::string("scale/") + scenario)) scale_error(scenario, scale_seeds);
    if (wanted("ten_minutes")) ten_minutes();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_refine_sim: %s\n", e.what());
    fs::remove_all(kRoot);
    return 1;
  }
  fs::remove_all(kRoot);
  std::printf("\nTargets (issues 4 and 19), seeds %d-%d (%zu per scenario; scale: %zu):\n",
              g_seeds.front(), g_seeds.back(), g_seeds.size(), scale_seeds.size());
  for (const std::string& line : g_targets) std::printf("%s\n", line.c_str());
  return 0;
}
