// Stages `ba` and `inspect` on keel-sim hauv-hull (seed 001 Sec. 4), per seed:
//   - whether `proposed` finds every foreign object >= 5 cm high (truth.yaml foreign_objects),
//     the cylinder's measured height vs 0.11 m, and shapes matching no object (false shapes);
//   - the DVL range residual sigma after GICP alone vs after `proposed` (target >= 3x smaller);
//   - solve time of `proposed` vs `naive` (target <= +25 %) and vs `geva`.
// Run: build/tests/bench/bench_hull_sim [seeds=3] [duration_s=0 (full survey)] [tracks=frontend]
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "tests/sim/simulator.h"
#include "worker/pipeline/ba_stage.h"
#include "worker/pipeline/inspect_stage.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace keel;

json run(pipeline::Stage& stage, const fs::path& mission, const fs::path& work,
         const json& options) {
  pipeline::StageContext context;
  context.mission_dir = mission;
  context.work_dir = work;
  context.options = options;
  return stage.run(context).report;
}

}  // namespace

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 3;
  const double duration_s = argc > 2 ? std::atof(argv[2]) : 0.0;
  const std::string tracks = argc > 3 ? argv[3] : "frontend";
  const fs::path root = fs::temp_directory_path() / ("keel_hull_bench_" + std::to_string(getpid()));
  std::printf("hauv-hull, %d seeds, duration %s, tracks=%s\n", seeds,
              duration_s > 0 ? std::to_string(duration_s).c_str() : "full", tracks.c_str());
  int all_found = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    const fs::path mission = root / ("seed" + std::to_string(seed));
    const fs::path work = mission / "work";
    sim::SimOptions o;
    o.scenario = "hauv-hull";
    o.seed = seed;
    o.out_dir = mission.string();
    o.duration_s = duration_s;
    sim::run_simulation(o);
    fs::create_directories(work);
    const json ba = run(*pipeline::make_ba_stage(), mission, work, {{"tracks", tracks}});
    const json in = run(*pipeline::make_inspect_stage(), mission, work, json::object());

    const json& modes = ba["modes"];
    const double t_naive = modes["naive"]["solve_time_s"].get<double>();
    const double t_geva = modes["geva"]["solve_time_s"].get<double>();
    const double t_prop = modes["proposed"]["solve_time_s"].get<double>();
    const double s_gicp = modes["proposed"]["dvl_residuals_gicp"]["sigma_m"].get<double>();
    const double s_prop = modes["proposed"]["dvl_residuals_final"]["sigma_m"].get<double>();
    std::printf("seed %d: %zu keyframes, %d landmarks, %d DVL returns used\n", seed,
                ba["input"]["keyframes"].get<size_t>(), ba["landmarks_triangulated"].get<int>(),
                ba["dvl_ranges_used"].get<int>());
    std::printf(
        "  DVL residual sigma: GICP %.4f m, proposed %.4f m (%.1fx smaller; target >= 3x)\n",
        s_gicp, s_prop, s_gicp / s_prop);
    std::printf(
        "  solve time: naive %.2f s, geva %.2f s, proposed %.2f s (%+.0f %% vs naive; "
        "target <= +25 %%)\n",
        t_naive, t_geva, t_prop, 100.0 * (t_prop / t_naive - 1.0));
    if (modes["proposed"].contains("T_world_model_vs_truth"))
      std::printf("  x_gM vs truth: %.3f m, %.2f deg (GICP alone: %.3f m, %.2f deg)\n",
                  modes["proposed"]["T_world_model_vs_truth"]["translation_error_m"].get<double>(),
                  modes["proposed"]["T_world_model_vs_truth"]["rotation_error_deg"].get<double>(),
                  ba["gicp"]["T_world_model_vs_truth"]["translation_error_m"].get<double>(),
                  ba["gicp"]["T_world_model_vs_truth"]["rotation_error_deg"].get<double>());
    bool every = true;
    for (const auto& obj : in["truth"]["objects"]) {
      const double h_true = obj["true_height_m"].get<double>();
      const bool found = obj["found"].get<bool>();
      if (h_true >= 0.05 && !found) every = false;
      std::printf("  %-8s true %.3f m: %s", obj["kind"].get<std::string>().c_str(), h_true,
                  found ? "found" : "MISSED");
      if (found)
        std::printf(", measured %.3f m (error %+.3f m)", obj["measured_height_m"].get<double>(),
                    obj["height_error_m"].get<double>());
      else if (obj.contains("nearest_shape_distance_m"))
        std::printf(" (nearest shape %.2f m away)", obj["nearest_shape_distance_m"].get<double>());
      std::printf("\n");
    }
    all_found += every;
    std::printf("  every object >= 5 cm found: %s; false shapes: %d of %zu shapes\n",
                every ? "yes" : "no", in["truth"]["false_shapes"].get<int>(), in["shapes"].size());
    std::fflush(stdout);
  }
  std::printf("seeds with every object >= 5 cm found: %d of %d\n", all_found, seeds);
  fs::remove_all(root);
  return 0;
}
