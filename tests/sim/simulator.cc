#include "tests/sim/simulator.h"

#include <yaml-cpp/yaml.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include "tests/sim/bag2_writer.h"
#include "tests/sim/bag_writer.h"
#include "tests/sim/bundle_files.h"
#include "tests/sim/calibration_error.h"
#include "tests/sim/gnss_sim.h"
#include "tests/sim/pose_table.h"
#include "tests/sim/rng.h"

namespace keel::sim {
namespace fs = std::filesystem;

namespace {

// ---- settings ------------------------------------------------------------------------

std::map<std::string, double*> setting_table(SensorSettings* s, ScenarioOptions* c) {
  return {
      {"imu.rate_hz", &s->imu.rate_hz},
      {"imu.gyro_noise_density", &s->imu.gyro_noise_density},
      {"imu.accel_noise_density", &s->imu.accel_noise_density},
      {"imu.gyro_random_walk", &s->imu.gyro_random_walk},
      {"imu.accel_random_walk", &s->imu.accel_random_walk},
      {"dvl.rate_hz", &s->dvl.rate_hz},
      {"dvl.velocity_sigma_rel", &s->dvl.velocity_sigma_rel},
      {"dvl.bias_random_walk_rel", &s->dvl.bias_random_walk_rel},
      {"dvl.dropout_mean_length_s", &s->dvl.dropout_mean_length_s},
      {"dvl.range_sigma", &s->dvl_range_sigma_m},
      {"dvl.beam_angle_deg", &s->dvl_beam_angle_deg},
      {"lidar.rate_hz", &s->lidar.rate_hz},
      {"lidar.range_sigma", &s->lidar.range_sigma_m},
      {"lidar.range_min", &s->lidar.range_min_m},
      {"lidar.range_max", &s->lidar.range_max_m},
      {"sonar.rate_hz", &s->sonar.rate_hz},
      {"sonar.fan_deg", &s->sonar.fan_deg},
      {"sonar.range_sigma", &s->sonar.range_sigma_m},
      {"sonar.range_max", &s->sonar.range_max_m},
      {"camera.rate_hz", &s->camera_rate_hz},
      {"camera.intensity_sigma", &s->camera.intensity_sigma},
      {"depth.rate_hz", &s->depth_rate_hz},
      {"depth.sigma", &s->depth_sigma_m},
      {"servo.rate_hz", &s->servo_rate_hz},
      {"gnss.rate_hz", &s->gnss.rate_hz},
      {"gnss.horizontal_sigma", &s->gnss.horizontal_sigma_m},
      {"gnss.vertical_sigma", &s->gnss.vertical_sigma_m},
      {"gnss.multipath_probability", &s->gnss.multipath_probability},
      {"gnss.multipath_radius", &s->gnss.multipath_radius_m},
      {"servo.sigma", &s->servo_sigma_rad},
      {"odometry.rate_hz", &s->odometry.rate_hz},
      {"odometry.scale_sigma", &s->odometry.scale_sigma},
      {"odometry.translation_walk", &s->odometry.translation_walk_per_sqrt_m},
      {"odometry.yaw_walk", &s->odometry.yaw_walk_per_sqrt_m},
      {"odometry.yaw_bias_sigma", &s->odometry.yaw_bias_sigma_per_m},
      {"odometry.degenerate_gain", &s->odometry.degenerate_gain},
      {"map.rate_hz", &s->map.rate_hz},
      {"map.sigma_translation", &s->map.sigma_translation_m},
      {"map.sigma_rotation", &s->map.sigma_rotation_rad},
      {"map.degenerate_walk", &s->map.degenerate_walk_per_sqrt_m},
      {"motion.speed", &c->motion.cruise_speed_mps},
      {"motion.ramp_s", &c->motion.ramp_s},
      {"motion.start_rest_s", &c->motion.start_rest_s},
      {"motion.roll_amplitude", &c->motion.roll_amplitude_rad},
      {"motion.pitch_amplitude", &c->motion.pitch_amplitude_rad},
      {"motion.heave_amplitude", &c->motion.heave_amplitude_m},
      {"hull.standoff", &c->hull_standoff_m},
      {"hull.landmark_density", &c->landmark_density_per_m2},
  };
}

const char* kIntegerSettings[] = {"lidar.points_per_ring", "lidar.rings", "sonar.beams"};
const char* kSwitchSettings[] = {"imu.noise", "dvl.noise", "camera.tracks"};

}  // namespace

std::string settings_help() {
  SensorSettings s;
  ScenarioOptions c;
  std::string out;
  for (const auto& [key, ptr] : setting_table(&s, &c)) out += key + " ";
  for (const char* key : kIntegerSettings) out += std::string(key) + " ";
  out +=
      "motion.laps hull.fouling_patches hull.cad(=FILE) hull.cad_scale hull.cad_z_down(0/1) "
      "hull.cad_draft hull.cad_survey_x ";
  for (const char* key : kSwitchSettings) out += std::string(key) + "(0/1) ";
  out +=
      "calibration_error.<sensor>={\"xyz_m\":[x,y,z],\"rpy_deg\":[r,p,y]} (mission.yaml's "
      "T_body_sensor = true * error; the truth stays in ground_truth/truth.yaml extrinsics) ";
  return out;
}

void apply_settings(const std::vector<std::string>& settings, SensorSettings* s,
                    ScenarioOptions* c) {
  auto table = setting_table(s, c);
  for (const std::string& item : settings) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument("--set " + item + ": expected key=value");
    const std::string key = item.substr(0, eq), text = item.substr(eq + 1);
    if (key == "hull.cad") {  // the one setting that is not a number: a mesh file
      if (text.empty()) throw std::invalid_argument("--set hull.cad: expected a mesh file");
      c->cad.path = text;
      continue;
    }
    double value;
    try {
      size_t used = 0;
      value = std::stod(text, &used);
      if (used != text.size() || !std::isfinite(value)) throw std::invalid_argument(text);
    } catch (const std::exception&) {
      throw std::invalid_argument("--set " + key + ": expected a finite number, got '" + text +
                                  "'");
    }
    if (auto it = table.find(key); it != table.end()) {
      if (value < 0.0 && key.find("gain") == std::string::npos)
        throw std::invalid_argument("--set " + key + ": must be >= 0, got " + text);
      // A range sensor's sigma goes into mission.yaml, whose readers require it positive.
      if (value <= 0.0 && key.size() > 11 && key.compare(key.size() - 11, 11, "range_sigma") == 0)
        throw std::invalid_argument("--set " + key +
                                    ": must be > 0 (the mission format requires a positive "
                                    "sigma; 1e-4 is all but noise-free), got " +
                                    text);
      *it->second = value;
      if (key == "motion.speed") c->speed_overridden = true;
      continue;
    }
    if (key == "motion.laps") {
      if (value < 1 || value > kMaxLaps || value != std::floor(value))
        throw std::invalid_argument("--set motion.laps: expected an integer in [1, " +
                                    std::to_string(kMaxLaps) +
                                    "] (times the path is flown), got '" + text + "'");
      c->motion.laps = int(value);
      continue;
    }
    if (key == "hull.fouling_patches") {
      if (value < 0 || value > kMaxFoulingPatches || value != std::floor(value))
        throw std::invalid_argument("--set hull.fouling_patches: expected an integer in [0, " +
                                    std::to_string(kMaxFoulingPatches) + "], got '" + text + "'");
      c->fouling_patches = int(value);
      continue;
    }
    if (key == "hull.cad_scale" || key == "hull.cad_draft" || key == "hull.cad_survey_x") {
      if (key == "hull.cad_scale" && !(value > 0.0))
        throw std::invalid_argument("--set hull.cad_scale: expected a factor > 0, got '" + text +
                                    "'");
      if (key == "hull.cad_draft" && !(value >= 0.0))
        throw std::invalid_argument(
            "--set hull.cad_draft: expected metres >= 0 (0: half the "
            "hull's depth), got '" +
            text + "'");
      if (key == "hull.cad_survey_x" && !(value >= 0.0 && value <= 1.0))
        throw std::invalid_argument(
            "--set hull.cad_survey_x: expected a value in [0, 1] (aft "
            "end to forward end), got '" +
            text + "'");
      (key == "hull.cad_scale"   ? c->cad.scale
       : key == "hull.cad_draft" ? c->cad.draft_m
                                 : c->cad.survey_x) = value;
      continue;
    }
    const bool integer =
        std::find_if(std::begin(kIntegerSettings), std::end(kIntegerSettings),
                     [&](const char* k) { return key == k; }) != std::end(kIntegerSettings);
    if (integer) {
      if (value < 1 || value > 100000 || value != std::floor(value))
        throw std::invalid_argument("--set " + key + ": expected an integer in [1, 100000]");
      if (key == "lidar.points_per_ring") s->lidar.points_per_ring = int(value);
      if (key == "lidar.rings") s->lidar.rings = int(value);
      if (key == "sonar.beams") s->sonar.beams = int(value);
      continue;
    }
    if (key == "imu.noise" || key == "dvl.noise" || key == "camera.tracks" ||
        key == "hull.cad_z_down") {
      if (value != 0.0 && value != 1.0)
        throw std::invalid_argument("--set " + key + ": expected 0 or 1");
      if (key == "hull.cad_z_down") c->cad.z_down = value != 0.0;
      if (key == "imu.noise") s->imu.noise = value != 0.0;
      if (key == "dvl.noise") s->dvl.noise = value != 0.0;
      if (key == "camera.tracks") s->feature_tracks = value != 0.0;
      continue;
    }
    throw std::invalid_argument("--set: unknown key '" + key + "'; valid keys: " + settings_help());
  }
  if (s->imu.rate_hz <= 0 || s->dvl.rate_hz <= 0 || s->lidar.rate_hz <= 0 ||
      s->sonar.rate_hz <= 0 || s->depth_rate_hz <= 0 || s->servo_rate_hz <= 0 ||
      s->odometry.rate_hz <= 0 || s->map.rate_hz <= 0 || s->gnss.rate_hz <= 0)
    throw std::invalid_argument("--set: every rate_hz must be > 0");
  if (!(s->gnss.horizontal_sigma_m > 0 && s->gnss.vertical_sigma_m > 0))
    throw std::invalid_argument("--set gnss.horizontal_sigma, gnss.vertical_sigma: must be > 0");
  if (!(s->gnss.multipath_probability >= 0 && s->gnss.multipath_probability <= 1))
    throw std::invalid_argument("--set gnss.multipath_probability: expected [0, 1]");
  if (c->motion.cruise_speed_mps <= 0)
    throw std::invalid_argument("--set motion.speed: must be > 0");
}

namespace {

// ---- mission.yaml helpers ----------------------------------------------------------------

void emit_pose(YAML::Emitter& y, const Pose3& T) {
  const Eigen::Quaterniond q(T.linear());
  y << YAML::Flow << YAML::BeginMap;
  y << YAML::Key << "translation" << YAML::Value << YAML::Flow << YAML::BeginSeq
    << T.translation().x() << T.translation().y() << T.translation().z() << YAML::EndSeq;
  y << YAML::Key << "rotation_xyzw" << YAML::Value << YAML::Flow << YAML::BeginSeq << q.x() << q.y()
    << q.z() << q.w() << YAML::EndSeq;
  y << YAML::EndMap;
}

void emit_vector(YAML::Emitter& y, const Eigen::Vector3d& v) {
  y << YAML::Flow << YAML::BeginSeq << v.x() << v.y() << v.z() << YAML::EndSeq;
}

// truth.yaml `changes`: what a later survey changed (docs/mission-format.md).
void emit_changes(YAML::Emitter& y, const std::vector<SceneChange>& changes) {
  y << YAML::Key << "changes" << YAML::Value << YAML::BeginSeq;
  for (const SceneChange& c : changes) {
    y << YAML::Flow << YAML::BeginMap;
    y << YAML::Key << "kind" << YAML::Value << c.kind;
    y << YAML::Key << "structure" << YAML::Value << c.structure;
    y << YAML::Key << "center" << YAML::Value;
    emit_vector(y, c.center);
    y << YAML::Key << "normal" << YAML::Value;
    emit_vector(y, c.normal);
    if (c.kind == "spall" || c.kind == "new_object") {
      y << YAML::Key << "width" << YAML::Value << c.width_m;
      y << YAML::Key << "footprint_height" << YAML::Value << c.footprint_height_m;
    }
    if (c.kind == "spall") y << YAML::Key << "depth" << YAML::Value << c.depth_m;
    if (c.kind != "spall") y << YAML::Key << "height" << YAML::Value << c.height_m;
    if (c.kind == "grown" || c.kind == "new" || c.kind == "removed")
      y << YAML::Key << "radius" << YAML::Value << c.radius_m;
    if (c.kind == "grown") {
      y << YAML::Key << "height_before" << YAML::Value << c.height_before_m;
      y << YAML::Key << "radius_before" << YAML::Value << c.radius_before_m;
    }
    if (c.object >= 0) y << YAML::Key << "object" << YAML::Value << c.object;
    y << YAML::EndMap;
  }
  y << YAML::EndSeq;
}

void write_text(const std::string& path, const std::string& text) {
  TextFile f(path);
  f.line(text);
  f.close();
}

// ---- scan jobs ------------------------------------------------------------------------

struct ScanJob {
  std::string sensor;  // lidar_h, lidar_v, sonar, cam0
  size_t index = 0;
  int64_t t_ns = 0;  // since mission start
};

struct ScanResult {
  PointCloud cloud;
  cv::Mat image;
  std::vector<TrackObservation> tracks;
};

std::string file_name(size_t index, const char* ext) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%06zu.%s", index, ext);
  return buffer;
}

Stream stream_of(const std::string& sensor) {
  if (sensor == "lidar_h") return Stream::kLidarH;
  if (sensor == "lidar_v") return Stream::kLidarV;
  if (sensor == "sonar") return Stream::kSonar;
  return Stream::kCamera;
}

// Runs fn(i) for i in [0, n) on `threads` threads.
void parallel_for(size_t n, int threads, const std::function<void(size_t)>& fn) {
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&] {
    for (size_t i = next++; i < n; i = next++) {
      try {
        fn(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(threads, 1); ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

std::vector<std::string> resolve_sensors(const SimOptions& options, const Scenario& scenario) {
  const std::set<std::string> known = {"imu",   "dvl",    "lidar_h", "lidar_v",
                                       "sonar", "camera", "depth",   "gnss"};
  std::vector<std::string> requested =
      options.sensors.empty() ? scenario.default_sensors : options.sensors;
  if (options.gnss) requested.push_back("gnss");
  std::vector<std::string> out;
  for (const auto& s : requested) {
    if (!known.count(s))
      throw std::invalid_argument("--sensors: unknown sensor '" + s +
                                  "' (expected imu,dvl,lidar_h,lidar_v,sonar,camera,depth,gnss)");
    const auto offers = [&](const std::vector<std::string>& list) {
      return std::find(list.begin(), list.end(), s) != list.end();
    };
    if (!offers(scenario.default_sensors) && !offers(scenario.optional_sensors))
      throw std::invalid_argument("--sensors: scenario " + scenario.name + " has no " + s);
    if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  }
  return out;
}

}  // namespace

SimSummary run_simulation(const SimOptions& options) {
  if (options.out_dir.empty()) throw std::invalid_argument("--out: output directory required");
  if (!(options.dvl_scale > 0.5 && options.dvl_scale < 1.5))
    throw std::invalid_argument("--dvl-scale: expected a value in (0.5, 1.5)");
  if (!(options.dvl_dropout_rate >= 0.0 && options.dvl_dropout_rate <= 0.9))
    throw std::invalid_argument("--dvl-dropout-rate: expected a value in [0, 0.9]");
  SensorSettings settings;
  ScenarioOptions scenario_options;
  std::vector<std::string> numeric_settings = options.settings;
  const CalibrationErrors calibration_errors = take_calibration_errors(&numeric_settings);
  apply_settings(numeric_settings, &settings, &scenario_options);
  settings.dvl.scale = options.dvl_scale;
  settings.dvl.dropout_rate = options.dvl_dropout_rate;
  scenario_options.survey = options.survey;

  const Scenario scenario = make_scenario(options.scenario, options.seed, scenario_options);
  const std::vector<std::string> sensors = resolve_sensors(options, scenario);
  auto has = [&](const std::string& s) {
    return std::find(sensors.begin(), sensors.end(), s) != sensors.end();
  };
  for (const auto& [name, error] : calibration_errors)
    if (!scenario.T_body_sensor.count(name))
      throw std::invalid_argument("--set " + std::string(kCalibrationErrorPrefix) + name +
                                  ": scenario " + scenario.name + " has no sensor '" + name + "'");
  // What the mission declares (mission.yaml, /tf_static); the data follow the truth.
  auto declared = [&](const std::string& name) {
    return declared_extrinsic(calibration_errors, name, scenario.T_body_sensor.at(name));
  };
  const double duration =
      options.duration_s > 0.0 ? options.duration_s : scenario.default_duration_s;
  if (!(duration > 0.0 && duration < 7 * 24 * 3600.0))
    throw std::invalid_argument("--duration: expected seconds in (0, 604800)");
  const bool hauv = scenario.platform == "hauv";
  // Sensor noise and timing of this survey; the scene comes from options.seed.
  const uint64_t seed = survey_seed(options.seed, options.survey);
  const TimeNs t0 = options.t0_ns + TimeNs(options.survey - 1) * 30 * 86400 * 1000000000LL;

  const fs::path out(options.out_dir);
  fs::create_directories(out / "ground_truth");
  SimSummary summary;
  summary.duration_s = duration;
  {
    double s, sd, sdd;
    scenario.motion->arc_length(duration, &s, &sd, &sdd);
    summary.path_length_m = s;
  }
  const PoseTable truth(*scenario.motion, duration);
  // Bags carry the same data as the files: a ROS1 bag and ROS 2 bags, each with a manifest
  // (manifest file, bag path) that maps the sensors to its topics.
  std::unique_ptr<BagSinks> bag;
  std::vector<std::pair<std::string, std::string>> bag_manifests;
  {
    auto sinks = std::make_unique<BagSinks>();
    if (options.write_bag) {
      sinks->add(std::make_unique<BagWriter>((out / "mission.bag").string()));
      bag_manifests.emplace_back("mission_bag.yaml", "mission.bag");
    }
    for (const auto& storage : options.bag2_storages) {
      Bag2Options bag2 = options.bag2;
      bag2.storage = storage;
      const std::string folder = storage == "sqlite3" ? "mission_db3" : "mission_" + storage;
      sinks->add(std::make_unique<Bag2Writer>((out / folder).string(), bag2));
      bag_manifests.emplace_back(folder + ".yaml", folder);
    }
    if (!sinks->empty()) bag = std::move(sinks);
  }
  if (bag) {
    // /tf_static: body -> each sensor frame a bag topic names (frame = sensor name), as a
    // robot's URDF publishes them; servo-tray sensors move, so they have no static edge.
    BagSink::TransformEdges edges;
    for (const auto& [name, T] : scenario.T_body_sensor) {
      const bool tray = std::find(scenario.tray_sensors.begin(), scenario.tray_sensors.end(),
                                  name) != scenario.tray_sensors.end();
      if (!tray) edges.emplace_back("base_link", name, declared(name));
    }
    bag->transforms("/tf_static", t0, edges);
  }

  YAML::Emitter sensors_yaml, sensors_bag_yaml;  // the sensors: lists of both manifests
  sensors_yaml.SetDoublePrecision(10);
  sensors_bag_yaml.SetDoublePrecision(10);
  sensors_yaml << YAML::BeginSeq;
  sensors_bag_yaml << YAML::BeginSeq;
  // Emits one sensor entry into both manifests; `source` is (key, file) for files and the
  // bag topic (empty: the bag does not carry it and the file is referenced instead).
  auto emit_sensor = [&](const std::string& name, const std::string& type, const std::string& key,
                         const std::string& file, const std::string& topic, double rate,
                         const std::function<void(YAML::Emitter&)>& extra) {
    for (int which = 0; which < 2; ++which) {
      YAML::Emitter& y = which == 0 ? sensors_yaml : sensors_bag_yaml;
      y << YAML::BeginMap << YAML::Key << "name" << YAML::Value << name;
      y << YAML::Key << "type" << YAML::Value << type;
      if (which == 1 && !topic.empty())
        y << YAML::Key << "topic" << YAML::Value << topic;
      else
        y << YAML::Key << key << YAML::Value << file;
      y << YAML::Key << "rate_hz" << YAML::Value << rate;
      y << YAML::Key << "T_body_sensor" << YAML::Value;
      emit_pose(y, declared(name));
      if (std::find(scenario.tray_sensors.begin(), scenario.tray_sensors.end(), name) !=
          scenario.tray_sensors.end())
        y << YAML::Key << "mounted_on" << YAML::Value << "servo";
      extra(y);
      y << YAML::EndMap;
    }
  };

  // ---- IMU ----
  if (has("imu")) {
    const auto samples = simulate_imu(*scenario.motion, duration, settings.imu, seed);
    TextFile f((out / "imu.csv").string());
    f.line("t,wx,wy,wz,ax,ay,az");
    for (const auto& s : samples) {
      const double v[6] = {s.gyro.x(),  s.gyro.y(),  s.gyro.z(),
                           s.accel.x(), s.accel.y(), s.accel.z()};
      f.row(t0 + s.t_ns, v, 6);
      if (bag) bag->imu("/imu/data", "imu", t0 + s.t_ns, s.gyro, s.accel);
    }
    f.close();
    summary.imu_samples = samples.size();
    emit_sensor(
        "imu", "imu", "file", "imu.csv", "/imu/data", settings.imu.rate_hz, [&](YAML::Emitter& y) {
          y << YAML::Key << "noise" << YAML::Value << YAML::BeginMap;
          y << YAML::Key << "gyro_noise_density" << YAML::Value << settings.imu.gyro_noise_density;
          y << YAML::Key << "accel_noise_density" << YAML::Value
            << settings.imu.accel_noise_density;
          y << YAML::Key << "gyro_random_walk" << YAML::Value << settings.imu.gyro_random_walk;
          y << YAML::Key << "accel_random_walk" << YAML::Value << settings.imu.accel_random_walk;
          y << YAML::EndMap;
        });
  }

  // ---- DVL velocity and (hull) four-beam ranges ----
  const auto beams = janus_beams(settings.dvl_beam_angle_deg);
  auto beam_ranges = [&](double t, const Pose3& T_body_dvl) {
    std::array<double, 4> ranges;
    const Pose3 T_world_dvl = truth.T_world_body(t) * T_body_dvl;
    for (int b = 0; b < 4; ++b) {
      RayHit hit;
      const Eigen::Vector3d dir = T_world_dvl.linear() * beams[b];
      ranges[b] =
          scenario.world->raycast(T_world_dvl.translation(), dir, 0.05, 50.0, &hit) && hit.returns
              ? hit.range_m
              : std::nan("");
    }
    return ranges;
  };
  if (has("dvl")) {
    auto T_body_dvl = [&](double t) { return scenario.T_body_sensor_at("dvl", t); };
    std::function<bool(double, const Pose3&)> lock;
    if (hauv) {  // bottom lock on the hull needs three of four beams
      lock = [&](double t, const Pose3& T) {
        const auto r = beam_ranges(t, T);
        return std::count_if(r.begin(), r.end(), [](double x) { return !std::isnan(x); }) >= 3;
      };
    }
    const auto samples =
        simulate_dvl(*scenario.motion, duration, T_body_dvl, settings.dvl, seed, lock);
    TextFile f((out / "dvl.csv").string());
    f.line("t,vx,vy,vz,valid");
    for (const auto& s : samples) {
      const Eigen::Vector3d v = s.valid ? s.velocity : Eigen::Vector3d::Zero();
      const double row[4] = {v.x(), v.y(), v.z(), s.valid ? 1.0 : 0.0};
      f.row(t0 + s.t_ns, row, 4);
      if (bag && s.valid)
        bag->twist("/dvl/twist", "dvl", t0 + s.t_ns, v,
                   settings.dvl.velocity_sigma_rel * s.velocity_true.norm());
    }
    f.close();
    summary.dvl_samples = samples.size();
    emit_sensor(
        "dvl", "dvl", "file", "dvl.csv", "/dvl/twist", settings.dvl.rate_hz, [&](YAML::Emitter& y) {
          y << YAML::Key << "noise" << YAML::Value << YAML::BeginMap;
          y << YAML::Key << "velocity_sigma_rel" << YAML::Value << settings.dvl.velocity_sigma_rel;
          y << YAML::Key << "bias_random_walk_rel" << YAML::Value
            << settings.dvl.bias_random_walk_rel;
          y << YAML::EndMap;
        });
    if (hauv) {
      Rng rng(seed, Stream::kDvlRanges);
      TextFile r((out / "dvl_ranges.csv").string());
      r.line("t,r0,r1,r2,r3");
      for (int64_t t_ns : sample_times_ns(settings.dvl.rate_hz, duration)) {
        const double t = t_ns * 1e-9;
        auto ranges = beam_ranges(t, scenario.T_body_sensor_at("dvl_ranges", t));
        for (double& x : ranges) {
          const double noise = settings.dvl_range_sigma_m * rng.gaussian();
          if (!std::isnan(x)) x += noise;
        }
        r.row(t0 + t_ns, ranges.data(), 4);
      }
      r.close();
      emit_sensor("dvl_ranges", "dvl_ranges", "file", "dvl_ranges.csv", "", settings.dvl.rate_hz,
                  [&](YAML::Emitter& y) {
                    y << YAML::Key << "beams" << YAML::Value << YAML::BeginSeq;
                    for (const auto& b : beams) emit_vector(y, b);
                    y << YAML::EndSeq;
                    y << YAML::Key << "noise" << YAML::Value << YAML::BeginMap << YAML::Key
                      << "range_sigma" << YAML::Value << settings.dvl_range_sigma_m << YAML::EndMap;
                  });
    }
  }

  // ---- servo (hull: whenever a tray sensor is simulated) ----
  if (scenario.has_servo && (has("dvl") || has("camera"))) {
    auto angle = [&](double t) { return scenario.servo_angle(t); };
    const auto samples =
        simulate_servo(angle, duration, settings.servo_rate_hz, settings.servo_sigma_rad, seed);
    TextFile f((out / "servo.csv").string()), g((out / "ground_truth" / "servo.csv").string());
    f.line("t,angle");
    g.line("t,angle");
    for (const auto& s : samples) {
      f.row(t0 + s.t_ns, &s.value, 1);
      g.row(t0 + s.t_ns, &s.value_true, 1);
    }
    f.close();
    g.close();
    emit_sensor("servo", "servo", "file", "servo.csv", "", settings.servo_rate_hz,
                [&](YAML::Emitter& y) {
                  y << YAML::Key << "axis" << YAML::Value;
                  emit_vector(y, scenario.servo_axis);
                  y << YAML::Key << "noise" << YAML::Value << YAML::BeginMap << YAML::Key
                    << "angle_sigma" << YAML::Value << settings.servo_sigma_rad << YAML::EndMap;
                });
  }

  // ---- depth ----
  if (has("depth")) {
    const auto samples =
        simulate_depth(*scenario.motion, duration, scenario.T_body_sensor.at("depth").translation(),
                       settings.depth_rate_hz, settings.depth_sigma_m, seed);
    TextFile f((out / "depth.csv").string());
    f.line("t,depth");
    for (const auto& s : samples) f.row(t0 + s.t_ns, &s.value, 1);
    f.close();
    emit_sensor("depth", "depth", "file", "depth.csv", "", settings.depth_rate_hz,
                [&](YAML::Emitter& y) {
                  y << YAML::Key << "noise" << YAML::Value << YAML::BeginMap << YAML::Key
                    << "depth_sigma" << YAML::Value << settings.depth_sigma_m << YAML::EndMap;
                });
  }

  // ---- GNSS (usv): fixes of the antenna, and which of them keel-sim corrupted ----
  if (has("gnss")) {
    const auto samples =
        simulate_gnss(*scenario.motion, duration, scenario.T_body_sensor.at("gnss").translation(),
                      scenario.gnss_environment, settings.gnss, seed);
    const LocalEnuFrame enu(scenario.origin);
    TextFile f((out / "gnss.csv").string()), g((out / "ground_truth" / "gnss.csv").string());
    f.line("t,latitude,longitude,height,status");
    g.line(
        "t,east,north,up,kind");  // the true antenna position; kind 0 clean, 1 multipath, 2 no fix
    for (const auto& s : samples) {
      // 12 significant digits: 1e-10 degrees, 0.01 mm (TextFile::row's 9 would be 1 cm).
      std::string text = format_seconds(t0 + s.t_ns) + ",nan,nan,nan,-1";
      if (s.kind != GnssFixKind::kNoFix) {
        const GeodeticPoint p = enu.to_geodetic(s.antenna_measured_world);
        char buffer[96];
        std::snprintf(buffer, sizeof buffer, ",%.12g,%.12g,%.6f,0", p.latitude_deg, p.longitude_deg,
                      p.height_m);
        text = format_seconds(t0 + s.t_ns) + buffer;
      }
      f.line(text);
      const double truth_row[4] = {s.antenna_true_world.x(), s.antenna_true_world.y(),
                                   s.antenna_true_world.z(), static_cast<double>(s.kind)};
      g.row(t0 + s.t_ns, truth_row, 4);
      summary.gnss_fixes += s.kind != GnssFixKind::kNoFix;
      summary.gnss_multipath += s.kind == GnssFixKind::kMultipath;
      summary.gnss_no_fix += s.kind == GnssFixKind::kNoFix;
    }
    f.close();
    g.close();
    emit_sensor(
        "gnss", "gnss", "file", "gnss.csv", "", settings.gnss.rate_hz, [&](YAML::Emitter& y) {
          y << YAML::Key << "noise" << YAML::Value << YAML::BeginMap;
          y << YAML::Key << "horizontal_sigma_m" << YAML::Value << settings.gnss.horizontal_sigma_m;
          y << YAML::Key << "vertical_sigma_m" << YAML::Value << settings.gnss.vertical_sigma_m;
          y << YAML::EndMap;
        });
  }

  // ---- scans and images: independent jobs on threads, written in chunks ----
  const double camera_rate =
      settings.camera_rate_hz > 0.0 ? settings.camera_rate_hz : scenario.camera_rate_hz;
  std::vector<ScanJob> jobs;
  std::map<std::string, std::vector<ScanJob>> per_sensor;
  auto schedule = [&](const std::string& sensor, double rate) {
    size_t i = 0;
    for (int64_t t_ns : sample_times_ns(rate, duration)) {
      // A lidar sweep must end inside the mission.
      if (sensor.rfind("lidar", 0) == 0 && t_ns * 1e-9 + 1.0 / rate > duration + 1e-9) break;
      per_sensor[sensor].push_back({sensor, i++, t_ns});
    }
    fs::create_directories(out / sensor);
  };
  if (has("lidar_h")) schedule("lidar_h", settings.lidar.rate_hz);
  if (has("lidar_v")) schedule("lidar_v", settings.lidar.rate_hz);
  if (has("sonar")) schedule("sonar", settings.sonar.rate_hz);
  if (has("camera")) schedule("cam0", camera_rate);
  for (const auto& [name, list] : per_sensor) jobs.insert(jobs.end(), list.begin(), list.end());
  std::stable_sort(jobs.begin(), jobs.end(),
                   [](const ScanJob& a, const ScanJob& b) { return a.t_ns < b.t_ns; });

  const bool tracks = hauv && settings.feature_tracks && has("camera");
  std::vector<std::vector<TrackObservation>> all_tracks(
      per_sensor.count("cam0") ? per_sensor["cam0"].size() : 0);
  std::atomic<size_t> total_points{0};
  const size_t chunk = 64;
  std::vector<ScanResult> results(chunk);
  for (size_t begin = 0; begin < jobs.size(); begin += chunk) {
    const size_t n = std::min(chunk, jobs.size() - begin);
    parallel_for(n, options.threads, [&](size_t k) {
      const ScanJob& job = jobs[begin + k];
      ScanResult& result = results[k];
      result = ScanResult{};
      Rng rng(seed, stream_of(job.sensor), job.index);
      const double t = job.t_ns * 1e-9;
      if (job.sensor == "cam0") {
        const Pose3 T_world_camera = truth.T_world_body(t) * scenario.T_body_sensor_at("cam0", t);
        result.image =
            render_image(*scenario.world, scenario.camera, T_world_camera, settings.camera, rng);
        if (!cv::imwrite((out / "cam0" / file_name(job.index, "png")).string(), result.image))
          throw std::runtime_error("cannot write " +
                                   (out / "cam0" / file_name(job.index, "png")).string());
        if (tracks)
          all_tracks[job.index] = visible_landmarks(
              *scenario.world, scenario.camera, T_world_camera, scenario.hull_world->landmarks());
        return;
      }
      if (job.sensor == "sonar") {
        const Pose3 T_world_sonar = truth.T_world_body(t) * scenario.T_body_sensor_at("sonar", t);
        result.cloud = simulate_sonar_ping(*scenario.world, T_world_sonar, settings.sonar, rng);
      } else {
        result.cloud = simulate_lidar_sweep(
            *scenario.world, truth, scenario.T_body_sensor.at(job.sensor), t, settings.lidar, rng);
      }
      result.cloud.t_ns = t0 + job.t_ns;
      result.cloud.frame = job.sensor;
      total_points += result.cloud.size();
      write_pcd_binary((out / job.sensor / file_name(job.index, "pcd")).string(), result.cloud);
    });
    if (bag) {  // in time order, so the bag's bytes do not depend on thread timing
      for (size_t k = 0; k < n; ++k) {
        const ScanJob& job = jobs[begin + k];
        if (job.sensor == "cam0")
          bag->image("/cam0/image_raw", "cam0", t0 + job.t_ns, results[k].image);
        else
          bag->cloud("/" + job.sensor + "/points", job.sensor, results[k].cloud);
      }
    }
  }
  summary.scans = jobs.size() - (per_sensor.count("cam0") ? per_sensor["cam0"].size() : 0);
  summary.scan_points = total_points;
  for (const auto& [sensor, list] : per_sensor) {
    TextFile index((out / sensor / "index.csv").string());
    index.line("t,file");
    for (const auto& job : list)
      index.line(format_seconds(t0 + job.t_ns) + "," +
                 file_name(job.index, sensor == "cam0" ? "png" : "pcd"));
    index.close();
  }
  for (const char* lidar : {"lidar_h", "lidar_v"}) {
    if (!per_sensor.count(lidar)) continue;
    emit_sensor(lidar, "lidar", "scans", lidar, std::string("/") + lidar + "/points",
                settings.lidar.rate_hz, [&](YAML::Emitter& y) {
                  y << YAML::Key << "point_time" << YAML::Value << YAML::BeginMap;
                  y << YAML::Key << "field" << YAML::Value << "time";
                  y << YAML::Key << "unit" << YAML::Value << "s";
                  y << YAML::Key << "reference" << YAML::Value << "scan_start" << YAML::EndMap;
                  y << YAML::Key << "range_m" << YAML::Value << YAML::Flow << YAML::BeginSeq
                    << settings.lidar.range_min_m << settings.lidar.range_max_m << YAML::EndSeq;
                  y << YAML::Key << "noise" << YAML::Value << YAML::BeginMap << YAML::Key
                    << "range_sigma" << YAML::Value << settings.lidar.range_sigma_m << YAML::EndMap;
                });
  }
  if (per_sensor.count("sonar")) {
    emit_sensor("sonar", "sonar", "scans", "sonar", "/sonar/points", settings.sonar.rate_hz,
                [&](YAML::Emitter& y) {
                  y << YAML::Key << "range_m" << YAML::Value << YAML::Flow << YAML::BeginSeq
                    << settings.sonar.range_min_m << settings.sonar.range_max_m << YAML::EndSeq;
                  y << YAML::Key << "noise" << YAML::Value << YAML::BeginMap << YAML::Key
                    << "range_sigma" << YAML::Value << settings.sonar.range_sigma_m << YAML::EndMap;
                });
  }
  if (per_sensor.count("cam0")) {
    summary.images = per_sensor["cam0"].size();
    const CameraModel& c = scenario.camera;
    emit_sensor(
        "cam0", "camera", "images", "cam0", "/cam0/image_raw", camera_rate, [&](YAML::Emitter& y) {
          y << YAML::Key << "camera" << YAML::Value << YAML::BeginMap;
          y << YAML::Key << "model" << YAML::Value << c.model_name();
          y << YAML::Key << "width" << YAML::Value << c.width << YAML::Key << "height"
            << YAML::Value << c.height;
          y << YAML::Key << "fx" << YAML::Value << c.fx << YAML::Key << "fy" << YAML::Value << c.fy;
          y << YAML::Key << "cx" << YAML::Value << c.cx << YAML::Key << "cy" << YAML::Value << c.cy;
          y << YAML::Key << "distortion" << YAML::Value << YAML::Flow << c.distortion;
          y << YAML::EndMap;
        });
  }
  sensors_yaml << YAML::EndSeq;
  sensors_bag_yaml << YAML::EndSeq;

  // ---- recorded SLAM trajectories and ground truth ----
  OdometryOptions odometry_options = settings.odometry;
  odometry_options.degenerate_axis_world = scenario.degenerate_axis_world;
  MapPoseOptions map_options = settings.map;
  map_options.degenerate_axis_world = scenario.degenerate_axis_world;
  const Trajectory odometry = simulate_odometry(truth, duration, t0, odometry_options, seed);
  const Trajectory map_poses = simulate_map_poses(truth, duration, t0, map_options, seed);
  summary.odometry_rmse_m = position_rmse(odometry, truth, t0);
  summary.map_rmse_m = position_rmse(map_poses, truth, t0);
  write_tum((out / "odometry.tum").string(), odometry);
  write_tum((out / "map_poses.tum").string(), map_poses);
  Trajectory true_trajectory;
  for (int64_t t_ns : sample_times_ns(100.0, duration))
    true_trajectory.push_back({t0 + t_ns, truth.T_world_body(t_ns * 1e-9)});
  write_tum((out / "ground_truth" / "trajectory.tum").string(), true_trajectory);
  if (bag) {
    for (const auto& p : map_poses) bag->pose("/slam/keyframes", "world", p);
    for (const auto& p : odometry) bag->odometry("/slam/odometry", "world", "base_link", p);
    bag->close();
  }

  // ---- hull: CAD model, landmarks, feature tracks ----
  if (hauv) {
    fs::create_directories(out / "cad");
    write_ply_binary((out / "cad" / "hull.ply").string(), scenario.cad_mesh);
    TextFile lm((out / "ground_truth" / "landmarks.csv").string());
    lm.line("id,x,y,z,on_cad,radius_m");
    char buffer[160];
    for (const auto& l : scenario.hull_world->landmarks()) {
      std::snprintf(buffer, sizeof(buffer), "%lld,%.9g,%.9g,%.9g,%d,%.6g",
                    static_cast<long long>(l.id), l.p_world.x(), l.p_world.y(), l.p_world.z(),
                    l.on_cad ? 1 : 0, l.radius_m);
      lm.line(buffer);
    }
    lm.close();
    if (tracks) {
      TextFile tf((out / "ground_truth" / "cam0_tracks.csv").string());
      tf.line("id,t,u,v");
      for (size_t i = 0; i < all_tracks.size(); ++i) {
        const std::string stamp = format_seconds(t0 + per_sensor["cam0"][i].t_ns);
        for (const auto& o : all_tracks[i]) {
          std::snprintf(buffer, sizeof(buffer), ",%.4f,%.4f", o.u, o.v);
          tf.line(std::to_string(o.landmark_id) + "," + stamp + buffer);
          ++summary.track_observations;
        }
      }
      tf.close();
    }
  }

  // ---- truth.yaml ----
  {
    YAML::Emitter y;
    y.SetDoublePrecision(10);
    y << YAML::BeginMap;
    y << YAML::Key << "keel_truth" << YAML::Value << 1;
    y << YAML::Key << "scenario" << YAML::Value << scenario.name;
    y << YAML::Key << "seed" << YAML::Value << options.seed;
    y << YAML::Key << "survey" << YAML::Value << options.survey;
    y << YAML::Key << "trajectory" << YAML::Value << "trajectory.tum";
    y << YAML::Key << "dvl_scale" << YAML::Value << settings.dvl.scale;
    // ground_truth/gnss.csv: the true antenna position of each fix and what keel-sim did to it.
    if (has("gnss")) y << YAML::Key << "gnss" << YAML::Value << "gnss.csv";
    y << YAML::Key << "extrinsics" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, T] : scenario.T_body_sensor) {
      if (name == "gnss" && !has("gnss")) continue;  // missions without gnss stay as they were
      y << YAML::Key << name << YAML::Value;
      emit_pose(y, T);
    }
    y << YAML::EndMap;
    // mission.yaml declares T_body_sensor = extrinsics[sensor] * calibration_error[sensor].
    if (!calibration_errors.empty()) {
      y << YAML::Key << "calibration_error" << YAML::Value << YAML::BeginMap;
      for (const auto& [name, error] : calibration_errors) {
        y << YAML::Key << name << YAML::Value;
        emit_pose(y, error);
      }
      y << YAML::EndMap;
    }
    if (hauv) {
      y << YAML::Key << "servo_angles" << YAML::Value << "servo.csv";
      y << YAML::Key << "T_world_cad" << YAML::Value;
      emit_pose(y, scenario.T_world_cad);
      y << YAML::Key << "foreign_objects" << YAML::Value << YAML::BeginSeq;
      for (const auto& o : scenario.foreign_objects) {
        y << YAML::Flow << YAML::BeginMap << YAML::Key << "kind" << YAML::Value << o.kind_name();
        y << YAML::Key << "center" << YAML::Value;
        emit_vector(y, o.center);
        y << YAML::Key << (o.kind == ForeignObject::Kind::kCylinder ? "axis" : "normal")
          << YAML::Value;
        emit_vector(y, o.axis);
        y << YAML::Key << "radius" << YAML::Value << o.radius_m;
        y << YAML::Key << "height" << YAML::Value << o.height_m << YAML::EndMap;
      }
      y << YAML::EndSeq;
      y << YAML::Key << "landmarks" << YAML::Value << "landmarks.csv";
      if (tracks) {
        y << YAML::Key << "feature_tracks" << YAML::Value << YAML::BeginMap << YAML::Key << "cam0"
          << YAML::Value << "cam0_tracks.csv" << YAML::EndMap;
      }
    }
    if (!scenario.changes.empty()) emit_changes(y, scenario.changes);
    y << YAML::EndMap;
    write_text((out / "ground_truth" / "truth.yaml").string(), y.c_str());
  }

  // ---- mission.yaml (and one manifest per bag: mission_bag.yaml, mission_mcap.yaml, ...) ----
  const std::string name = scenario.name + "-seed" + std::to_string(options.seed) +
                           (options.survey > 1 ? "-survey" + std::to_string(options.survey) : "");
  for (size_t which = 0; which <= bag_manifests.size(); ++which) {
    YAML::Emitter y;
    y.SetDoublePrecision(10);
    y << YAML::BeginMap;
    y << YAML::Key << "keel_mission" << YAML::Value << 1;
    y << YAML::Key << "name" << YAML::Value << name;
    y << YAML::Key << "platform" << YAML::Value << scenario.platform;
    y << YAML::Key << "body_frame" << YAML::Value << "base_link";
    y << YAML::Key << "world_frame" << YAML::Value << "world";
    if (has("gnss")) {
      y << YAML::Key << "origin" << YAML::Value << YAML::BeginMap;
      y << YAML::Key << "latitude_deg" << YAML::Value << scenario.origin.latitude_deg;
      y << YAML::Key << "longitude_deg" << YAML::Value << scenario.origin.longitude_deg;
      y << YAML::Key << "height_m" << YAML::Value << scenario.origin.height_m;
      y << YAML::EndMap;
    }
    if (which > 0) y << YAML::Key << "bag" << YAML::Value << bag_manifests[which - 1].second;
    y << YAML::Key << "sensors" << YAML::Value
      << YAML::Load((which == 0 ? sensors_yaml : sensors_bag_yaml).c_str());
    y << YAML::Key << "trajectories" << YAML::Value << YAML::BeginMap;
    if (which == 0) {
      y << YAML::Key << "map" << YAML::Value << "map_poses.tum";
      y << YAML::Key << "odometry" << YAML::Value << "odometry.tum";
    } else {
      y << YAML::Key << "map" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "topic"
        << YAML::Value << "/slam/keyframes" << YAML::EndMap;
      y << YAML::Key << "odometry" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
        << "topic" << YAML::Value << "/slam/odometry" << YAML::EndMap;
    }
    y << YAML::Key << "ground_truth" << YAML::Value << "ground_truth/trajectory.tum";
    y << YAML::EndMap;
    y << YAML::Key << "ground_truth" << YAML::Value << "ground_truth/truth.yaml";
    if (hauv) y << YAML::Key << "cad_mesh" << YAML::Value << "cad/hull.ply";
    y << YAML::EndMap;
    write_text((out / (which == 0 ? "mission.yaml" : bag_manifests[which - 1].first)).string(),
               y.c_str());
  }
  return summary;
}

}  // namespace keel::sim
