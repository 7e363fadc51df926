// keel-sim's library entry point: builds a scenario, simulates every requested sensor and
// writes a mission bundle (docs/mission-format.md) with ground truth, optionally ROS1 and ROS 2
// bags of the same data.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/time.h"
#include "tests/sim/bag2_writer.h"
#include "tests/sim/camera_sim.h"
#include "tests/sim/inertial_sensors.h"
#include "tests/sim/range_sensors.h"
#include "tests/sim/scenarios.h"
#include "tests/sim/slam_recording.h"

namespace keel::sim {

// Every tunable figure, defaults from seed 000 Table I / seed 001 unless noted.
struct SensorSettings {
  ImuOptions imu;
  DvlOptions dvl;
  double dvl_range_sigma_m = 0.003;  // four-beam ranges (issue 3)
  double dvl_beam_angle_deg = 30.0;  // RDI Janus
  SpinningLidarOptions lidar;
  ProfilingSonarOptions sonar;
  CameraRenderOptions camera;
  double camera_rate_hz = 0.0;  // <= 0: scenario default
  double depth_rate_hz = 10.0, depth_sigma_m = 0.01;
  double servo_rate_hz = 20.0, servo_sigma_rad = 5.0 * M_PI / 180.0;  // seed 001 Eq. (10)
  GnssOptions gnss;
  OdometryOptions odometry;
  MapPoseOptions map;
  bool feature_tracks = true;  // hauv-hull: ground-truth tracks of landmark blobs
};

struct SimOptions {
  std::string scenario = "usv-bridge";
  uint64_t seed = 1;
  // 1: the first survey; 2, 3, ...: the same scene surveyed again 30 days apart, with the
  // known changes of truth.yaml's `changes`, its own motion and sensor noise (usv-bridge,
  // hauv-hull).
  int survey = 1;
  std::string out_dir;
  double duration_s = 0.0;           // <= 0: the scenario's full path
  std::vector<std::string> sensors;  // imu,dvl,lidar_h,lidar_v,sonar,camera,depth,gnss; empty: all
                                     //   default ones (gnss is optional)
  bool gnss = false;                 // adds gnss to the sensors (usv scenarios)
  double dvl_scale = 1.0;
  double dvl_dropout_rate = 0.0;
  bool write_bag = false;
  // ROS 2 bags of the same data: "mcap" -> mission_mcap/ + mission_mcap.yaml, "sqlite3" ->
  // mission_db3/ + mission_db3.yaml (bag2.storage is set per entry).
  std::vector<std::string> bag2_storages;
  Bag2Options bag2;
  int threads = 2;
  TimeNs t0_ns = 1700000000LL * 1000000000LL;  // mission start stamp
  // "key=value" overrides (see settings_help()); "calibration_error.<sensor>=<pose JSON>"
  // perturbs the sensor's declared extrinsic (calibration_error.h)
  std::vector<std::string> settings;
};

struct SimSummary {
  double duration_s = 0.0;
  double path_length_m = 0.0;
  size_t imu_samples = 0, dvl_samples = 0, scans = 0, scan_points = 0, images = 0;
  size_t track_observations = 0;
  size_t gnss_fixes = 0, gnss_multipath = 0, gnss_no_fix = 0;
  double odometry_rmse_m = 0.0, map_rmse_m = 0.0;
};

// Throws std::invalid_argument on bad options (unknown scenario, sensor or setting).
SimSummary run_simulation(const SimOptions& options);

// Applies "key=value" settings; throws naming the key and listing the valid ones.
void apply_settings(const std::vector<std::string>& settings, SensorSettings* sensors,
                    ScenarioOptions* scenario);
std::string settings_help();

}  // namespace keel::sim
