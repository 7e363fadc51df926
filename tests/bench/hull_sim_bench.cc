// Stages `ba` and `inspect` on keel-sim hauv-hull (seed 001 Sec. 4, issue 6's targets), per seed:
//   - whether `proposed` finds every foreign object >= 5 cm high (truth.yaml foreign_objects),
//     the cylinder's measured height vs 0.11 m, and shapes matching no object (false shapes);
//   - the DVL range residual sigma after GICP alone vs after `proposed` (target >= 3x smaller);
//   - solve time of `proposed` vs `naive` (target <= +25 %) and vs `geva` (target: less);
// then a table of the seeds with their sum and a pass/fail line per target over the seeds
// (issue 18: the timing targets on the sums, the DVL target on a fouled hull on the robust
// sigma).
// Run: build/tests/bench/bench_hull_sim [seeds=3 | first-last] [duration_s=0 (full survey)]
//                                       [tracks=frontend|ground_truth] [ba option=value]...
//                                       [sim.<keel-sim --set key>=value]...
// Environment: KEEL_HULL_BENCH_DIR=<dir> keeps the missions and stage outputs there (a mission
// already simulated there is reused); KEEL_HULL_BENCH_REUSE_BA=1 also reuses a kept `ba`
// report (inspect-only iterations); KEEL_HULL_BENCH_RUNS=N (default 2) runs the `ba` stage N
// times per seed and compares each mode's fastest solve.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"
#include "core/robust_spread.h"
#include "worker/io/yaml_json.h"
#include "worker/stages/ba/stage.h"
#include "worker/stages/inspect/stage.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace keel;

constexpr double kMinObjectHeightM = 0.05;     // "every foreign object at least 5 cm high"
constexpr double kCylinderToleranceM = 0.015;  // "within 1.5 cm"
constexpr double kDvlSigmaRatio = 3.0;         // "at least 3x smaller"
constexpr double kMaxTimeOverNaive = 0.25;     // "at most 25 % more time than naive"

json run(pipeline::Stage& stage, const fs::path& mission, const fs::path& work,
         const json& options) {
  pipeline::StageContext context;
  context.mission_dir = mission;
  context.work_dir = work;
  context.options = options;
  return stage.run(context).report;
}

// Whether any BA camera saw the object's top within 5 m: a run shorter than the survey does not
// reach every object, and an object no image shows cannot be found.
bool surveyed(const json& object, const pipeline::BaSolution& solution,
              const sim::CameraModel& camera) {
  const json& c = object["center"];
  const json& a = object.contains("axis") ? object["axis"] : object["normal"];
  const double h = object["height"].get<double>();
  const Eigen::Vector3d top(c[0].get<double>() + h * a[0].get<double>(),
                            c[1].get<double>() + h * a[1].get<double>(),
                            c[2].get<double>() + h * a[2].get<double>());
  for (const Pose3& T_world_camera : solution.T_world_camera) {
    const Eigen::Vector3d p = T_world_camera.inverse() * top;
    Eigen::Vector2d uv;
    if (p.z() > 0 && p.z() < 5.0 && camera.project(p, &uv)) return true;
  }
  return false;
}

struct Tally {
  int pass = 0, runs = 0;
  void add(bool ok) { pass += ok, ++runs; }
  const char* verdict() const { return runs > 0 && pass == runs ? "PASS" : "FAIL"; }
};

}  // namespace

int main(int argc, char** argv) {
  // "3" runs seeds 1..3; "2-3" runs seeds 2..3 (one seed at a time on a loaded machine).
  const std::string seed_arg = argc > 1 ? argv[1] : "3";
  const size_t dash = seed_arg.find('-');
  const int first_seed = dash == std::string::npos ? 1 : std::atoi(seed_arg.c_str());
  const int last_seed = std::atoi(seed_arg.c_str() + (dash == std::string::npos ? 0 : dash + 1));
  const int seeds = last_seed - first_seed + 1;
  const double duration_s = argc > 2 ? std::atof(argv[2]) : 0.0;
  const std::string tracks = argc > 3 ? argv[3] : "frontend";
  json ba_options = {{"tracks", tracks}};
  std::vector<std::string> sim_settings;  // sim.<keel-sim --set key>=value
  std::string mission_suffix;
  for (int i = 4; i < argc; ++i) {  // further ba options, key=value (value: JSON or a string)
    const std::string arg = argv[i];
    const size_t eq = arg.find('=');
    if (eq == std::string::npos) {
      std::fprintf(stderr, "bench_hull_sim: expected key=value, got '%s'\n", argv[i]);
      return 2;
    }
    if (arg.rfind("sim.", 0) == 0) {
      sim_settings.push_back(arg.substr(4));
      std::string name = arg.substr(4);  // a folder name: sim.hull.cad=/a/b.stl -> hull.cad=b.stl
      if (const size_t slash = name.rfind('/'); slash != std::string::npos)
        name = name.substr(0, name.find('=') + 1) + name.substr(slash + 1);
      mission_suffix += "_" + name;
      continue;
    }
    const json value = json::parse(arg.substr(eq + 1), nullptr, /*allow_exceptions=*/false);
    ba_options[arg.substr(0, eq)] = value.is_discarded() ? json(arg.substr(eq + 1)) : value;
  }
  const char* keep = std::getenv("KEEL_HULL_BENCH_DIR");
  const bool reuse_ba = keep && std::getenv("KEEL_HULL_BENCH_REUSE_BA");
  const char* runs_env = std::getenv("KEEL_HULL_BENCH_RUNS");
  const int runs = std::max(1, runs_env ? std::atoi(runs_env) : 2);
  const fs::path root =
      keep ? fs::path(keep)
           : fs::temp_directory_path() / ("keel_hull_bench_" + std::to_string(getpid()));
  std::printf("hauv-hull, %d seeds, duration %s, ba options %s, keel-sim settings '%s'\n", seeds,
              duration_s > 0 ? std::to_string(duration_s).c_str() : "full",
              ba_options.dump().c_str(), mission_suffix.c_str());
  Tally found_all, cylinder, clean, dvl, dvl_robust, time_naive, time_geva;
  std::vector<std::string> table;                          // one row per seed, printed at the end
  double total_naive = 0, total_geva = 0, total_prop = 0;  // solve times summed over seeds, s
  for (int seed = first_seed; seed <= last_seed; ++seed) {
    const fs::path mission =
        root / ("seed" + std::to_string(seed) + "_" +
                (duration_s > 0 ? std::to_string(int(duration_s)) + "s" : std::string("full")) +
                mission_suffix);
    const fs::path work = mission / ("work_" + tracks);
    sim::SimOptions o;
    o.scenario = "hauv-hull";
    o.seed = seed;
    o.out_dir = mission.string();
    o.duration_s = duration_s;
    o.settings = sim_settings;
    if (!keep || !fs::exists(mission / "mission.yaml")) sim::run_simulation(o);
    fs::create_directories(work);
    const fs::path ba_report = work / "ba_report.json";
    json ba;
    // The fastest solve of each mode over `runs` stage runs: per-iteration times on this
    // shared machine vary by a third from run to run, the iteration counts do not.
    std::map<std::string, std::vector<double>> times;  // per mode, one per stage run
    if (reuse_ba && fs::exists(ba_report)) {
      std::ifstream(ba_report) >> ba;
    } else {
      for (int r = 0; r < runs; ++r) {
        const json again = run(*pipeline::make_ba_stage(), mission, work, ba_options);
        if (r == 0) ba = again;
        for (const auto& [mode, m] : again["modes"].items())
          times[mode].push_back(m["solve_time_s"].get<double>());
      }
      for (auto& [mode, t] : times) {
        std::sort(t.begin(), t.end());
        ba["modes"][mode]["solve_time_s"] = t.front();
      }
      if (keep) std::ofstream(ba_report) << ba.dump(1);
    }
    const json in = run(*pipeline::make_inspect_stage(), mission, work, json::object());
    if (keep) std::ofstream(work / "inspect_report.json") << in.dump(1);

    const json& modes = ba["modes"];
    const double t_naive = modes["naive"]["solve_time_s"].get<double>();
    const double t_geva = modes["geva"]["solve_time_s"].get<double>();
    const double t_prop = modes["proposed"]["solve_time_s"].get<double>();
    const double s_gicp = modes["proposed"]["dvl_residuals_gicp"]["sigma_m"].get<double>();
    const double s_prop = modes["proposed"]["dvl_residuals_final"]["sigma_m"].get<double>();
    double robust_ratio = 0.0;  // GICP's robust sigma over proposed's (0: a report without it)
    std::printf("seed %d: %zu keyframes, %d landmarks, %d DVL returns used\n", seed,
                ba["input"]["keyframes"].get<size_t>(), ba["landmarks_triangulated"].get<int>(),
                ba["dvl_ranges_used"].get<int>());
    if (ba["frontend"]["ran"].get<bool>()) {
      std::printf(
          "  frontend: %d verified matches, %d tracks, %d triangulated, %d dropped after "
          "initialisation (gate %.2f px, %d observations removed)\n",
          ba["frontend"]["verified_matches"].get<int>(), ba["frontend"]["tracks"].get<int>(),
          ba["landmarks_triangulated"].get<int>(),
          ba["landmarks_dropped_after_initialisation"].get<int>(),
          ba.value("post_initialisation_gate_px", 0.0),
          ba.value("observations_dropped_after_initialisation", 0));
    }
    std::printf(
        "  DVL residual sigma: GICP %.4f m, proposed %.4f m (%.1fx smaller; target >= 3x)\n",
        s_gicp, s_prop, s_gicp / s_prop);
    const json& r_gicp = modes["proposed"]["dvl_residuals_gicp"];
    const json& r_prop = modes["proposed"]["dvl_residuals_final"];
    if (r_prop.contains("robust_sigma_m")) {  // a report kept from before has none
      // Beams that see foreign structure 5-18 cm proud dominate the standard deviation on a
      // fouled hull; 1.4826 MAD measures the spread of the rest. Printed, not a target.
      const double rs_gicp = r_gicp["robust_sigma_m"].get<double>();
      const double rs_prop = r_prop["robust_sigma_m"].get<double>();
      robust_ratio = rs_gicp / rs_prop;
      std::printf(
          "  DVL residual robust sigma (1.4826 MAD): GICP %.4f m, proposed %.4f m (%.1fx)\n",
          rs_gicp, rs_prop, rs_gicp / rs_prop);
    }
    std::printf(
        "  solve time (fastest of %d stage runs): naive %.2f s, geva %.2f s, proposed %.2f s "
        "(%+.0f %% vs naive; target <= +25 %%)\n",
        reuse_ba ? 1 : runs, t_naive, t_geva, t_prop, 100.0 * (t_prop / t_naive - 1.0));
    if (runs > 1 && !times.empty()) {  // how far apart runs of one mode are
      std::printf("  solve time over the %d runs, fastest-median-slowest:", runs);
      for (const char* mode : {"naive", "geva", "proposed"}) {
        const std::vector<double>& t = times[mode];
        std::printf(" %s %.2f-%.2f-%.2f s;", mode, t.front(), robust_spread(t).median, t.back());
      }
      std::printf("\n");
    }
    // Time follows the iteration count. A solve is within 1e-4 of its final cost by iteration
    // 6-7; what follows are steps that lower it by ~2e-6 of itself (or, with `geva` on a fouled
    // hull, steps Levenberg-Marquardt rejects) until Ceres's function tolerance (1e-6) is met,
    // and their number differs between modes and seeds.
    std::printf("  iterations (rejected): ");
    for (const char* mode : {"naive", "geva", "proposed"}) {
      const json& m = modes[mode];
      const auto& costs = m["cost_per_iteration"];
      // The iteration from which the cost stays within 1e-4 of its final value.
      size_t settled = costs.size();
      while (settled > 0 &&
             costs[settled - 1].get<double>() <= (1.0 + 1e-4) * m["final_cost"].get<double>())
        --settled;
      std::printf("%s %d (%d), within 1e-4 of the final cost from iteration %zu, %.2f s/it; ", mode,
                  m["iterations"].get<int>(), m["unsuccessful_steps"].get<int>(), settled,
                  m["solve_time_s"].get<double>() / m["iterations"].get<int>());
    }
    std::printf("\n");
    if (ba["gicp"].contains("T_world_model_vs_truth")) {
      // Translation error along the hull (model x) and across it (model y, z): x is nearly
      // unobservable on the prismatic mid-body the lanes survey.
      auto print_error = [](const char* name, const json& e) {
        if (!e.contains("translation_error_model_axes_m")) {  // a report kept from before
          std::printf("%s %.3f m, %.2f deg", name, e.at("translation_error_m").get<double>(),
                      e.at("rotation_error_deg").get<double>());
          return;
        }
        const json& axes = e["translation_error_model_axes_m"];
        std::printf("%s %.3f m along, %.3f m across, %.2f deg", name, axes[0].get<double>(),
                    std::hypot(axes[1].get<double>(), axes[2].get<double>()),
                    e["rotation_error_deg"].get<double>());
      };
      print_error("  x_gM vs truth: GICP", ba["gicp"]["T_world_model_vs_truth"]);
      for (const char* mode : {"naive", "geva", "proposed"}) {
        std::printf("; ");
        print_error(mode, modes[mode]["T_world_model_vs_truth"]);
        const json& sigma =
            modes[mode].value("T_world_model_translation_sigma_model_axes_m", json());
        if (sigma.is_array()) std::printf(" (sigma along %.3f m)", sigma[0].get<double>());
      }
      std::printf("\n");
    }

    std::ifstream solution_file(work / pipeline::kBaSolutionFile);
    const pipeline::BaSolution solution =
        pipeline::ba_solution_from_json(json::parse(solution_file), "ba_solution.json");
    const sim::CameraModel camera = sim::make_scenario("hauv-hull", seed).camera;
    // truth.yaml's foreign_objects, in the order of the inspect report's truth.objects.
    const json truth_objects =
        io::load_yaml_file(mission / "ground_truth" / "truth.yaml")["foreign_objects"];
    bool every = true, cylinder_ok = false;
    int found_count = 0, surveyed_count = 0;
    double cylinder_error = NAN;
    const json& objects = in["truth"]["objects"];
    for (size_t k = 0; k < objects.size(); ++k) {
      const json& obj = objects[k];
      const double h_true = obj["true_height_m"].get<double>();
      const bool found = obj["found"].get<bool>();
      const bool seen = surveyed(truth_objects[k], solution, camera);
      if (h_true >= kMinObjectHeightM && seen && !found) every = false;
      if (h_true >= kMinObjectHeightM && seen) ++surveyed_count, found_count += found;
      std::printf("  %-8s true %.3f m: %s", obj["kind"].get<std::string>().c_str(), h_true,
                  found ? "found" : (seen ? "MISSED" : "not surveyed"));
      if (found) {
        const double error = obj["height_error_m"].get<double>();
        std::printf(", measured %.3f m (error %+.3f m)", obj["measured_height_m"].get<double>(),
                    error);
        if (obj["kind"] == "cylinder") {
          cylinder_ok = std::abs(error) <= kCylinderToleranceM;
          cylinder_error = error;
        }
      } else if (obj.contains("nearest_shape_distance_m")) {
        std::printf(" (nearest shape %.2f m away)", obj["nearest_shape_distance_m"].get<double>());
      }
      std::printf("\n");
    }
    const int false_shapes = in["truth"]["false_shapes"].get<int>();
    std::printf(
        "  every surveyed object >= 5 cm found: %s; shapes on clean hull: %d, extra shapes on "
        "objects: %d, of %zu shapes (tau %.4f m)\n",
        every ? "yes" : "no", false_shapes, in["truth"]["extra_shapes_on_objects"].get<int>(),
        in["shapes"].size(), in["tau_m"].get<double>());
    found_all.add(every);
    cylinder.add(cylinder_ok);
    clean.add(false_shapes == 0);
    dvl.add(s_gicp / s_prop >= kDvlSigmaRatio);
    dvl_robust.add(robust_ratio >= kDvlSigmaRatio);
    char row[256];
    std::snprintf(
        row, sizeof(row),
        "| %d | %d / %d | %+.3f | %d | %d | %.1fx | %.1fx | %.2f / %.2f / %.2f | %+.0f %% |", seed,
        found_count, surveyed_count, cylinder_error, false_shapes,
        in.value("shapes_rejected_few_views", 0), s_gicp / s_prop, robust_ratio, t_naive, t_geva,
        t_prop, 100.0 * (t_prop / t_naive - 1.0));
    table.push_back(row);
    time_naive.add(t_prop <= (1.0 + kMaxTimeOverNaive) * t_naive);
    time_geva.add(t_prop < t_geva);
    total_naive += t_naive, total_geva += t_geva, total_prop += t_prop;
    std::fflush(stdout);
  }
  std::printf(
      "\n| seed | objects >= 5 cm found / surveyed | cylinder error, m | shapes on clean hull | "
      "shapes dropped (< min_shape_views views) | DVL sigma GICP/proposed | DVL robust sigma "
      "GICP/proposed | solve naive / geva / proposed, s | proposed vs naive |\n"
      "|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& row : table) std::printf("%s\n", row.c_str());
  std::printf("| sum | | | | | | | %.2f / %.2f / %.2f | %+.0f %% |\n\n", total_naive, total_geva,
              total_prop, 100.0 * (total_prop / total_naive - 1.0));
  std::printf("targets over %d seeds (passes / seeds):\n", seeds);
  std::printf("  %s every surveyed foreign object >= 5 cm found: %d / %d\n", found_all.verdict(),
              found_all.pass, found_all.runs);
  std::printf("  %s cylinder height within 1.5 cm: %d / %d\n", cylinder.verdict(), cylinder.pass,
              cylinder.runs);
  std::printf("  %s no shape on clean hull: %d / %d\n", clean.verdict(), clean.pass, clean.runs);
  std::printf(
      "  %s DVL residual sigma >= 3x smaller than GICP alone: %d / %d (the target on a "
      "clean hull)\n",
      dvl.verdict(), dvl.pass, dvl.runs);
  // On a fouled hull the beams that hit a patch 5-18 cm proud are real structure, not error:
  // issue 18 judges the target there on the robust sigma (1.4826 MAD).
  std::printf(
      "  %s DVL residual robust sigma >= 3x smaller than GICP alone: %d / %d (the target "
      "on a fouled hull)\n",
      dvl_robust.verdict(), dvl_robust.pass, dvl_robust.runs);
  // Issue 18: the timing targets are judged on the solve times summed over the seeds (on the
  // fouled hull); per seed, which mode stops first turns on Ceres's stopping tail.
  std::printf(
      "  %s proposed <= +25 %% time vs naive, summed over the seeds: %+.0f %% (per seed: "
      "%d / %d)\n",
      total_prop <= (1.0 + kMaxTimeOverNaive) * total_naive ? "PASS" : "FAIL",
      100.0 * (total_prop / total_naive - 1.0), time_naive.pass, time_naive.runs);
  std::printf(
      "  %s proposed faster than geva, summed over the seeds: %+.0f %% (per seed: %d / "
      "%d)\n",
      total_prop < total_geva ? "PASS" : "FAIL", 100.0 * (total_prop / total_geva - 1.0),
      time_geva.pass, time_geva.runs);
  if (!keep) fs::remove_all(root);
  return 0;
}
