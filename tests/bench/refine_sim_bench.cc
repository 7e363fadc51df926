// The `refine` stage on keel-sim missions (IMU + DVL; recorded MAP and odometry), seed 000
// Table II style. Not a CTest test; run build/tests/bench/bench_refine_sim [seeds].
//   1. usv-bridge (220 s) and usv-corridor (its full path), seeds 1..N (5): translational ATE
//      (SE(3) Umeyama) of the MAP poses, the refinement without and with DVL, and the reduction
//      with DVL vs MAP (target >= 40 % in both scenarios);
//   2. the same missions with a 2 % DVL scale error (keel-sim --dvl-scale 1.02): ATE with s_d
//      estimated vs s_d held at the known 1.02 (target: within 10 %);
//   3. the solve time of a 10-minute usv-bridge mission (speed lowered so the path takes
//      600 s; target <= 5 s on 2 cores).
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"
#include "worker/pipeline/refine_stage.h"

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
  o.sensors = {"imu", "dvl"};
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

void table_ii(const std::string& scenario, int seeds) {
  std::printf("\n%s: ATE rmse (m), SE(3) Umeyama, keyframes vs ground truth\n", scenario.c_str());
  // The target (issue 4, paper Table II) is what DVL fusion adds: with vs without DVL.
  std::printf("%6s %10s %12s %10s %12s %10s %8s %10s\n", "seed", "MAP", "refined-noDVL", "refined",
              "DVL-vs-noDVL", "vs-MAP", "s_d", "solve_s");
  Mean map, without, with, reduction, reduction_vs_map;
  for (int seed = 1; seed <= seeds; ++seed) {
    const fs::path mission = simulate(scenario, seed, 1.0);
    const json r = run_refine(mission, json::object());
    const double a_map = ate(r, "map"), a_without = ate(r, "refined_without_dvl"),
                 a_with = ate(r, "refined_with_dvl");
    const double red = 100.0 * (1.0 - a_with / a_without);
    const double red_map = 100.0 * (1.0 - a_with / a_map);
    std::printf("%6d %10.4f %12.4f %10.4f %11.1f%% %9.1f%% %8.4f %10.2f\n", seed, a_map, a_without,
                a_with, red, red_map, r["dvl"]["dvl_scale"]["value"].get<double>(),
                r["solver"]["total_time_s"].get<double>());
    map.add(a_map);
    without.add(a_without);
    with.add(a_with);
    reduction.add(red);
    reduction_vs_map.add(red_map);
    fs::remove_all(mission);
  }
  std::printf(
      "%6s %10.4f %12.4f %10.4f %11.1f%% %9.1f%%   (means; DVL fusion lowers the mean ATE by "
      "%.1f%%, target >= 40%%)\n",
      "mean", map.value(), without.value(), with.value(), reduction.value(),
      reduction_vs_map.value(), 100.0 * (1.0 - with.value() / without.value()));
  const double fusion = 100.0 * (1.0 - with.value() / without.value());
  target(scenario, "DVL fusion: mean ATE lower than without DVL by", fusion, " %", ">= 40 %",
         fusion >= 40.0);
}

void scale_error(const std::string& scenario, int seeds) {
  std::printf("\n%s with a 2%% DVL scale error (s_d = 1.02): ATE rmse (m)\n", scenario.c_str());
  std::printf("%6s %12s %12s %10s %16s\n", "seed", "s_d estim.", "s_d fixed", "ratio",
              "s_d estimate");
  Mean est, fixed;
  for (int seed = 1; seed <= seeds; ++seed) {
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
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 5;
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
      if (wanted(std::string("fusion/") + scenario)) table_ii(scenario, seeds);
    for (const char* scenario : {"usv-bridge", "usv-corridor"})
      if (wanted(std::string("scale/") + scenario)) scale_error(scenario, seeds);
    if (wanted("ten_minutes")) ten_minutes();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_refine_sim: %s\n", e.what());
    fs::remove_all(kRoot);
    return 1;
  }
  fs::remove_all(kRoot);
  std::printf("\nTargets (issue 4), %d seeds per scenario:\n", seeds);
  for (const std::string& line : g_targets) std::printf("%s\n", line.c_str());
  return 0;
}
