// Refine solver on a synthetic 10-minute USV mission (200 Hz IMU, 20 Hz DVL, 1 Hz keyframes,
// drifting odometry with a 20 s degenerate corridor, loop closures): prints the solve time
// (target <= 5 s on 2 cores) and the ATE with and without DVL. Not a CTest test; run
// build/tests/bench/bench_refine [duration_s] [all]; `all` adds every keyframe's covariance.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>

#include "tests/worker/slam/synthetic_mission.h"
#include "worker/slam/refine_solver.h"
#include "worker/slam/trajectory_metrics.h"

namespace {

using keel::slam::Alignment;
using keel::slam::RefineOptions;
using keel::slam::RefineResult;

void report(const char* name, const RefineResult& r, const keel::Trajectory& truth) {
  const auto ate = keel::slam::absolute_trajectory_error(truth, r.trajectory(), Alignment::kSE3);
  const auto& s = r.summary;
  std::printf(
      "%-12s total %.2f s (solve %.2f s, covariance %.2f s), %d iterations, %d keyframes, "
      "%d IMU / %d DVL / %d odometry / %d loop factors, %d degenerate\n"
      "%-12s ATE rmse %.3f m mean %.3f m max %.3f m, rotation rmse %.3f deg; s_d %.4f +- %.4f\n",
      name, s.total_time_s, s.solve_time_s, s.covariance_time_s, s.iterations, s.num_keyframes,
      s.num_imu_factors, s.num_dvl_factors, s.num_odometry_factors, s.num_loop_closures,
      s.num_degenerate_keyframes, "", ate.translation_m.rmse, ate.translation_m.mean,
      ate.translation_m.max, ate.rotation_deg.rmse, r.dvl_scale, r.dvl_scale_sigma);
}

}  // namespace

int main(int argc, char** argv) {
  keel::slam::testing::SyntheticMissionOptions o;
  o.duration_s = argc > 1 ? std::atof(argv[1]) : 600.0;
  o.dvl_scale = 1.02;
  o.loop_closures = true;
  const auto t0 = std::chrono::steady_clock::now();
  const auto m = keel::slam::testing::make_synthetic_mission(o);
  const double gen_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "mission: %.0f s, %zu IMU, %zu DVL samples, %zu keyframes, %zu loop closures "
      "(generated in %.2f s)\n",
      o.duration_s, m.input.imu.size(), m.input.dvl.size(), m.input.keyframes.size(),
      m.input.loop_closures.size(), gen_s);
  const auto odom =
      keel::slam::absolute_trajectory_error(m.ground_truth, m.odometry, Alignment::kSE3);
  std::printf("%-12s ATE rmse %.3f m mean %.3f m max %.3f m\n", "odometry", odom.translation_m.rmse,
              odom.translation_m.mean, odom.translation_m.max);
  RefineOptions with_dvl;
  if (argc > 2 && std::string(argv[2]) == "all") {
    with_dvl.covariances = keel::slam::CovarianceScope::kAll;
  }
  const std::clock_t cpu0 = std::clock();
  report("with DVL", keel::slam::refine_trajectory(m.input, with_dvl), m.ground_truth);
  std::printf("%-12s CPU time %.2f s (all threads)\n", "",
              static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC);
  RefineOptions without_dvl;
  without_dvl.use_dvl = false;
  report("without DVL", keel::slam::refine_trajectory(m.input, without_dvl), m.ground_truth);
  return 0;
}
