// keel-sim: writes a synthetic mission bundle with ground truth (docs/design.md "Processes").
//   keel-sim --scenario usv-bridge|usv-corridor|hauv-hull --seed N --out DIR [--duration S]
//            [--sensors imu,dvl,lidar_h,lidar_v,sonar,camera,depth,gnss] [--gnss]
//            [--dvl-scale 1.02]
//            [--dvl-dropout-rate R] [--bag] [--bag2 mcap,sqlite3] [--survey N]
//            [--set key=value ...]
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <exception>

#include "tests/sim/simulator.h"

int main(int argc, char** argv) {
  keel::sim::SimOptions options;
  CLI::App app{"keel-sim: synthetic inspection missions with ground truth"};
  app.add_option("--scenario", options.scenario, "usv-bridge | usv-corridor | hauv-hull")
      ->check(CLI::IsMember({"usv-bridge", "usv-corridor", "hauv-hull"}));
  app.add_option("--seed", options.seed, "random seed (same seed, same bytes)");
  app.add_option("--survey", options.survey,
                 "1 = first survey; 2, 3, ... = the same scene again with known changes "
                 "(truth.yaml `changes`; usv-bridge, hauv-hull)")
      ->check(CLI::Range(1, 100));
  app.add_option("--out", options.out_dir, "output mission folder")->required();
  app.add_option("--duration", options.duration_s, "seconds (default: the scenario's whole path)");
  app.add_option("--sensors", options.sensors,
                 "comma-separated subset of imu,dvl,lidar_h,lidar_v,sonar,camera,depth")
      ->delimiter(',');
  app.add_option("--dvl-scale", options.dvl_scale, "true DVL scale factor s_d (seed 000 Eq. (8))");
  app.add_option("--dvl-dropout-rate", options.dvl_dropout_rate,
                 "fraction of DVL samples lost (bursts)");
  app.add_flag("--gnss", options.gnss,
               "usv: also write gnss.csv (fixes with dropouts under the deck and multipath near "
               "the piers), ground_truth/gnss.csv and the mission's origin");
  app.add_flag("--bag", options.write_bag, "also write mission.bag and mission_bag.yaml");
  app.add_option("--bag2", options.bag2_storages,
                 "also write ROS 2 bags of the same data: mcap (mission_mcap/, mission_mcap.yaml) "
                 "and/or sqlite3 (mission_db3/, mission_db3.yaml)")
      ->delimiter(',')
      ->check(CLI::IsMember({"mcap", "sqlite3"}));
  app.add_option("--bag2-compression", options.bag2.compression,
                 "MCAP chunk compression: zstd (default), lz4 or none")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}));
  app.add_option("--bag2-split-bytes", options.bag2.max_file_bytes,
                 "split ROS 2 bags into files of about this many bytes (0: one file)");
  app.add_option("--threads", options.threads, "worker threads")->check(CLI::Range(1, 64));
  app.add_option("--set", options.settings, "key=value overrides: " + keel::sim::settings_help());
  CLI11_PARSE(app, argc, argv);
  try {
    const auto start = std::chrono::steady_clock::now();
    const auto s = keel::sim::run_simulation(options);
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf(
        "keel-sim: %s seed %llu -> %s\n  duration %.1f s, path %.1f m, imu %zu, dvl %zu, scans %zu "
        "(%zu points), images %zu, track observations %zu\n  odometry RMSE %.3f m, MAP RMSE %.3f "
        "m, "
        "%.1f s wall\n",
        options.scenario.c_str(), static_cast<unsigned long long>(options.seed),
        options.out_dir.c_str(), s.duration_s, s.path_length_m, s.imu_samples, s.dvl_samples,
        s.scans, s.scan_points, s.images, s.track_observations, s.odometry_rmse_m, s.map_rmse_m,
        elapsed);
    if (s.gnss_fixes + s.gnss_no_fix > 0)
      std::printf("  gnss fixes %zu (multipath %zu), no fix %zu\n", s.gnss_fixes, s.gnss_multipath,
                  s.gnss_no_fix);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "keel-sim: %s\n", e.what());
    return 1;
  }
}
