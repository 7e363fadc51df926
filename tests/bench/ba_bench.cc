// Model-assisted BA (seed 001) on simulated hull surveys: per-mode solve time and iterations
// of the small test problem, then a 1,000-keyframe, 50,000-landmark survey (target <= 3 min on
// 2 cores), `proposed` vs `naive` (target <= +25 %) and vs `geva`. Not a CTest test; run
//   build/tests/bench/bench_ba [sparse_schur|iterative_schur] [lanes] [keyframes_per_lane]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "tests/worker/ba/ba_synthetic.h"
#include "worker/ba/model_assisted_ba.h"

namespace {

using keel::ba::BaMode;
using keel::ba::BaModeResult;
using keel::ba::BaResult;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void report(const char* title, const keel::testing::SyntheticHull& sim, const BaResult& r,
            double total_s) {
  std::printf(
      "%s: %zu keyframes, %d landmarks, %d DVL beams; total %.1f s "
      "(SLAM initialisation %.1f s, %d iterations)\n",
      title, sim.problem.keyframes.size(), r.landmarks_triangulated, r.dvl_ranges_used, total_s,
      r.initialisation.solve_time_s, r.initialisation.iterations);
  for (const BaModeResult& m : r.modes) {
    int on = 0;
    for (const auto& l : m.landmarks) on += l.lambda;
    std::printf("  %-9s %6.1f s  %3d iterations  cost %.4g -> %.4g  lambda=1 %.3f  %s\n",
                keel::ba::to_string(m.mode), m.solve_time_s, m.iterations, m.initial_cost,
                m.final_cost, double(on) / m.landmarks.size(), m.converged ? "converged" : "");
  }
  const BaModeResult* naive = r.find(BaMode::kNaive);
  const BaModeResult* geva = r.find(BaMode::kGeva);
  const BaModeResult* proposed = r.find(BaMode::kProposed);
  if (naive && geva && proposed) {
    std::printf(
        "  proposed vs naive %+.1f %% (target <= +25 %%), geva vs naive %+.1f %%, "
        "proposed vs geva %+.1f %%\n",
        100.0 * (proposed->solve_time_s / naive->solve_time_s - 1.0),
        100.0 * (geva->solve_time_s / naive->solve_time_s - 1.0),
        100.0 * (proposed->solve_time_s / geva->solve_time_s - 1.0));
  }
}

void run(const char* title, const keel::testing::SyntheticHullOptions& sim_options,
         const keel::ba::BaOptions& options) {
  auto start = std::chrono::steady_clock::now();
  const keel::testing::SyntheticHull sim = keel::testing::make_synthetic_hull(sim_options);
  std::printf("%s: simulated in %.1f s\n", title, seconds_since(start));
  start = std::chrono::steady_clock::now();
  const BaResult r = keel::ba::run_model_assisted_ba(sim.problem, options);
  report(title, sim, r, seconds_since(start));
}

}  // namespace

int main(int argc, char** argv) {
  keel::ba::BaOptions options;
  options.num_threads = 2;
  if (argc > 1) options.linear_solver = argv[1];
  std::printf("linear solver %s, %d threads\n", options.linear_solver.c_str(), options.num_threads);

  keel::testing::SyntheticHullOptions small;  // the monocular test problem
  small.bump_height_m = 0.11;
  run("small (monocular test hull)", small, options);

  // 10 lanes x 100 keyframes along a 30 m stretch of a gently curved hull, ~50,000 landmarks.
  keel::testing::SyntheticHullOptions large;
  large.lanes = argc > 2 ? std::atoi(argv[2]) : 10;
  const int per_lane = argc > 3 ? std::atoi(argv[3]) : 100;
  large.lane_half_length_m = 0.5 * (per_lane - 1) * large.keyframe_spacing_m;
  large.half_length_m = large.lane_half_length_m + 1.5;
  large.half_width_m = 0.5 * (large.lanes - 1) * large.lane_spacing_m + 1.5;
  large.curvature_x = 0.002;
  large.curvature_y = 0.05;
  large.grid_m = 0.1;
  large.landmarks = 60'000;  // ~50,000 are seen twice and triangulated
  large.bump_landmarks = 200;
  run("large", large, options);
  return 0;
}
