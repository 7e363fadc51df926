// The mission manifest (`mission.yaml`, docs/mission-format.md) as a JSON contract.
// The YAML file is converted to JSON by worker/io and read here strictly: unknown, missing or
// mistyped fields fail with a ContractError naming the path, e.g.
// `sensors[2].T_body_sensor.rotation_xyzw: expected 4 numbers, got 3`.
// Paths stay as written (relative to the bundle); worker/io resolves and checks them.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace keel::proto {

constexpr int kMissionFormatVersion = 1;

enum class SensorType { kImu, kDvl, kDvlRanges, kLidar, kSonar, kCamera, kDepth, kServo, kGnss };

std::string to_string(SensorType type);
// Fails naming `path` and the known types for an unknown name.
SensorType sensor_type_from_string(std::string_view text, const std::string& path = "type");
// "imu, dvl, dvl_ranges, lidar, sonar, camera, depth, servo, gnss"
std::string known_sensor_types();

// T_body_sensor: maps points in the sensor frame into the body frame.
struct Extrinsic {
  std::array<double, 3> translation = {0.0, 0.0, 0.0};  // m
  std::array<double, 4> rotation_xyzw = {0.0, 0.0, 0.0,
                                         1.0};  // unit quaternion (normalised on read)

  nlohmann::json to_json() const;
  // Fails when |q| differs from 1 by more than 1e-3, or on non-finite numbers.
  static Extrinsic from_json(const nlohmann::json& value, const std::string& path);
};

// Noise figures; defaults are seed 000 Table I (IMU: Xsens MTi-30, DVL: Water Linked A50,
// lidar: VLP-16) and seed 001 (DVL ranges: Eq. (14), servo: Eq. (10)).
struct ImuNoise {
  double gyro_noise_density = 5.7e-4;   // rad/s/sqrt(Hz)
  double accel_noise_density = 9.4e-4;  // m/s^2/sqrt(Hz)
  double gyro_random_walk = 3.7e-6;     // rad/s^2/sqrt(Hz)
  double accel_random_walk = 2.4e-6;    // m/s^3/sqrt(Hz)
};
struct DvlNoise {
  double velocity_sigma_rel = 1.0e-3;    // sigma = velocity_sigma_rel * |v| (seed 000, A50 +-0.1%)
  double bias_random_walk_rel = 1.0e-4;  // (seed 000 Table I)
};
struct RangeNoise {
  double range_sigma = 0.01;  // m (seed 000 Table I, VLP-16)
};
struct DvlRangesNoise {
  double range_sigma = 0.003;  // m (seed 001 Eq. (14): 3 mm at 1-2 m standoff)
};
struct CameraNoise {
  double pixel_sigma = 0.007;  // px (seed 000 Table I, simulated image noise)
};
struct DepthNoise {
  double depth_sigma = 0.01;  // m; no paper figure: a typical pressure-depth sensor
};
struct ServoNoise {
  double angle_sigma = 0.0873;  // rad, 5 degrees (seed 001 Eq. (10))
};
// Used for fixes whose message gives no covariance (NavSatFix COVARIANCE_TYPE_UNKNOWN, or a
// CSV without covariance columns). No paper figure: a single-frequency receiver's spread.
struct GnssNoise {
  double horizontal_sigma_m = 1.5;
  double vertical_sigma_m = 3.0;
};

struct SensorNoise {
  ImuNoise imu;
  DvlNoise dvl;
  RangeNoise range;  // lidar, sonar, depth-camera scans
  DvlRangesNoise dvl_ranges;
  CameraNoise camera;
  DepthNoise depth;
  ServoNoise servo;
  GnssNoise gnss;
};

enum class TimeUnit { kSeconds, kMilliseconds, kMicroseconds, kNanoseconds };
// scan_start / scan_end: the point's time is an offset from the scan's header stamp, which
// marks the first (Velodyne, Ouster) or the last (some Hesai and Livox set-ups) point of the
// sweep; absolute: the point's time is a time since the epoch (Livox, Hesai float64).
enum class TimeReference { kScanStart, kScanEnd, kAbsolute };
std::string to_string(TimeUnit unit);
std::string to_string(TimeReference reference);
double seconds_per_unit(TimeUnit unit);

// Per-point time of a scan (Velodyne: float s from sweep start; Ouster: uint32 ns). A split
// time is two integer fields, whole seconds and nanoseconds (`field: [time_sec, time_nsec]`
// in mission.yaml): `nsec_field` is then the second name and `unit` is seconds for `field`.
struct PointTimeSpec {
  std::string field = "time";
  TimeUnit unit = TimeUnit::kSeconds;
  TimeReference reference = TimeReference::kScanStart;
  std::string nsec_field;  // empty: one field (last, so {field, unit, reference} still works)

  bool is_split() const { return !nsec_field.empty(); }

  nlohmann::json to_json() const;
  static PointTimeSpec from_json(const nlohmann::json& value, const std::string& path);
};

// Raw lidar packets on a bag topic (velodyne_msgs/VelodyneScan): the sensor model whose firing
// table decodes them, and optionally the driver's calibration YAML (per-laser corrections),
// relative to the bundle. Without it the model's published factory table is used.
struct LidarPacketSpec {
  std::string model;  // VLP16, VLP32C, HDL32E
  std::string calibration;

  nlohmann::json to_json() const;
  static LidarPacketSpec from_json(const nlohmann::json& value, const std::string& path);
};
// Known packet models: "VLP16, VLP32C, HDL32E".
std::string known_lidar_packet_models();

enum class CameraModel { kPinhole, kKannalaBrandt };

struct CameraSpec {
  CameraModel model = CameraModel::kPinhole;
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::vector<double> distortion;  // pinhole: [] or [k1, k2, p1, p2]; kannala_brandt: [k1..k4]

  nlohmann::json to_json() const;
  static CameraSpec from_json(const nlohmann::json& value, const std::string& path);
};

struct SensorSpec {
  std::string name;  // unique, [A-Za-z0-9_]+
  SensorType type = SensorType::kImu;
  // Exactly one data source: a CSV `file` (streams), a `scans` or `images` folder, or a bag
  // `topic` (the manifest then has `bag:`). `depth` takes `file` (pressure depth) or `scans`
  // (depth-camera frames).
  std::string file;
  std::string scans;
  std::string images;
  std::string topic;
  std::string frame_id;                    // frame in the bag's /tf_static; empty = the sensor name
  double rate_hz = 0.0;                    // nominal
  std::optional<Extrinsic> T_body_sensor;  // absent: take it from /tf_static (bags) or unknown
  SensorNoise noise;                       // only the entry of this type is read/written
  std::optional<PointTimeSpec> point_time;       // scan sensors
  std::optional<LidarPacketSpec> packets;        // lidar on a topic of raw packets
  std::optional<std::array<double, 2>> range_m;  // scan sensors and dvl_ranges: [min, max]
  std::vector<std::array<double, 3>> beams;      // dvl_ranges: 4 unit vectors (DVL frame)
  std::optional<CameraSpec> camera;              // cameras (required for them)
  // Servo trays (seed 001's HAUV): a servo's rotation axis in its own frame, and, on a sensor
  // riding the tray, the servo's name. T_body_sensor is then the extrinsic at angle 0.
  std::optional<std::array<double, 3>> axis;  // servo only; default [0, 0, 1]
  std::string mounted_on;                     // name of a servo sensor, or empty

  bool is_stream() const { return !file.empty(); }
  bool is_scans() const;   // scans folder, or a scan-type sensor on a bag topic
  bool is_images() const;  // images folder, or a camera on a bag topic
  const std::string& effective_frame() const { return frame_id.empty() ? name : frame_id; }

  nlohmann::json to_json() const;
  static SensorSpec from_json(const nlohmann::json& value, const std::string& path);
};

// A recorded trajectory: a TUM file or a bag topic (PoseStamped or Odometry).
struct TrajectorySpec {
  std::string file;
  std::string topic;

  nlohmann::json to_json() const;  // a plain string for files, {topic: ...} for topics
  static TrajectorySpec from_json(const nlohmann::json& value, const std::string& path);
};

// Where the world frame is on the earth: the world frame is the local east-north-up frame
// whose origin is this WGS 84 point (height above the ellipsoid). Required with gnss sensors;
// products carry it so that they can be placed on a map.
struct GeoOrigin {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;

  nlohmann::json to_json() const;
  static GeoOrigin from_json(const nlohmann::json& value, const std::string& path);
};

enum class Platform { kUsv, kHauv, kOther };
std::string to_string(Platform platform);

struct MissionManifest {
  int keel_mission = kMissionFormatVersion;
  std::string name;
  Platform platform = Platform::kOther;
  std::string body_frame = "base_link";
  std::string world_frame = "world";
  std::optional<GeoOrigin> origin;  // world frame = ENU at this point
  std::string bag;                  // optional ROS1 bag
  std::vector<SensorSpec> sensors;
  // Known names: map, odometry, ground_truth (ordered by name).
  std::map<std::string, TrajectorySpec> trajectories;
  std::string loop_closures;  // optional loops.csv
  std::string ground_truth;   // optional truth.yaml
  std::string cad_mesh;       // optional CAD model

  const SensorSpec* find_sensor(std::string_view name) const;
  // Throws std::out_of_range naming the sensor and the mission's sensors.
  const SensorSpec& sensor(std::string_view name) const;

  nlohmann::json to_json() const;
  // Checks names, uniqueness, sources, rates and the cross-field rules of
  // docs/mission-format.md. `path` prefixes field paths ("" for a whole document).
  static MissionManifest from_json(const nlohmann::json& value, const std::string& path = "");
};

}  // namespace keel::proto
