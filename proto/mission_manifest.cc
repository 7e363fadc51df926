#include "proto/mission_manifest.h"

#include <cmath>
#include <regex>
#include <stdexcept>

#include "proto/contract_error.h"

namespace keel::proto {

namespace {

constexpr std::pair<SensorType, const char*> kSensorTypeNames[] = {
    {SensorType::kImu, "imu"},
    {SensorType::kDvl, "dvl"},
    {SensorType::kDvlRanges, "dvl_ranges"},
    {SensorType::kLidar, "lidar"},
    {SensorType::kSonar, "sonar"},
    {SensorType::kCamera, "camera"},
    {SensorType::kDepth, "depth"},
    {SensorType::kServo, "servo"},
    {SensorType::kGnss, "gnss"}};

constexpr std::pair<TimeUnit, const char*> kUnitNames[] = {{TimeUnit::kSeconds, "s"},
                                                           {TimeUnit::kMilliseconds, "ms"},
                                                           {TimeUnit::kMicroseconds, "us"},
                                                           {TimeUnit::kNanoseconds, "ns"}};

constexpr std::pair<TimeReference, const char*> kReferenceNames[] = {
    {TimeReference::kScanStart, "scan_start"},
    {TimeReference::kScanEnd, "scan_end"},
    {TimeReference::kAbsolute, "absolute"}};

const char* const kLidarPacketModels[] = {"VLP16", "VLP32C", "HDL32E"};

constexpr std::pair<Platform, const char*> kPlatformNames[] = {
    {Platform::kUsv, "usv"}, {Platform::kHauv, "hauv"}, {Platform::kOther, "other"}};

constexpr std::pair<CameraModel, const char*> kCameraModelNames[] = {
    {CameraModel::kPinhole, "pinhole"}, {CameraModel::kKannalaBrandt, "kannala_brandt"}};

const char* const kTrajectoryNames[] = {"map", "odometry", "ground_truth"};

template <typename Enum, size_t N>
std::string name_of(const std::pair<Enum, const char*> (&table)[N], Enum value) {
  for (const auto& [v, name] : table)
    if (v == value) return name;
  return "unknown";
}

template <typename Enum, size_t N>
std::string names_of(const std::pair<Enum, const char*> (&table)[N]) {
  std::string out;
  for (const auto& [v, name] : table) out += (out.empty() ? "" : ", ") + std::string(name);
  return out;
}

template <typename Enum, size_t N>
Enum parse_enum(const std::pair<Enum, const char*> (&table)[N], const nlohmann::json& value,
                const std::string& path, const char* what) {
  const auto text = FieldReader::convert<std::string>(value, path);
  for (const auto& [v, name] : table)
    if (text == name) return v;
  throw ContractError(path + ": unknown " + what + " '" + text + "' (known: " + names_of(table) +
                      ")");
}

double finite_number(const nlohmann::json& value, const std::string& path) {
  const double x = FieldReader::convert<double>(value, path);
  if (!std::isfinite(x)) throw ContractError(path + ": expected a finite number");
  return x;
}

double positive_number(const FieldReader& r, const char* field) {
  const double x = finite_number(r.at(field), r.child(field));
  if (!(x > 0.0))
    throw ContractError(r.child(field) + ": expected a positive number, got " + std::to_string(x));
  return x;
}

double optional_positive(const FieldReader& r, const char* field, double fallback) {
  return r.has(field) ? positive_number(r, field) : fallback;
}

template <size_t N>
std::array<double, N> fixed_numbers(const nlohmann::json& value, const std::string& path) {
  const std::string expected = "expected " + std::to_string(N) + " numbers";
  if (!value.is_array())
    throw ContractError(path + ": " + expected + ", got " + json_type_name(value));
  if (value.size() != N)
    throw ContractError(path + ": " + expected + ", got " + std::to_string(value.size()));
  std::array<double, N> out{};
  for (size_t i = 0; i < N; ++i)
    out[i] = finite_number(value[i], path + "[" + std::to_string(i) + "]");
  return out;
}

std::vector<double> numbers(const nlohmann::json& value, const std::string& path) {
  if (!value.is_array())
    throw ContractError(path + ": expected array of numbers, got " + json_type_name(value));
  std::vector<double> out;
  for (size_t i = 0; i < value.size(); ++i)
    out.push_back(finite_number(value[i], path + "[" + std::to_string(i) + "]"));
  return out;
}

void check_name(const std::string& name, const std::string& path, const char* pattern_text,
                const std::regex& pattern) {
  if (!std::regex_match(name, pattern))
    throw ContractError(path + ": '" + name + "' does not match " + pattern_text);
}

bool is_scan_type(SensorType type) {
  return type == SensorType::kLidar || type == SensorType::kSonar || type == SensorType::kDepth;
}

void read_noise(const FieldReader& sensor, SensorSpec& spec) {
  const bool has = sensor.has("noise");
  const nlohmann::json empty = nlohmann::json::object();
  FieldReader r(has ? sensor.at("noise") : empty, sensor.child("noise"));
  SensorNoise& n = spec.noise;
  switch (spec.type) {
    case SensorType::kImu:
      r.reject_unknown(
          {"gyro_noise_density", "accel_noise_density", "gyro_random_walk", "accel_random_walk"});
      n.imu.gyro_noise_density =
          optional_positive(r, "gyro_noise_density", n.imu.gyro_noise_density);
      n.imu.accel_noise_density =
          optional_positive(r, "accel_noise_density", n.imu.accel_noise_density);
      n.imu.gyro_random_walk = optional_positive(r, "gyro_random_walk", n.imu.gyro_random_walk);
      n.imu.accel_random_walk = optional_positive(r, "accel_random_walk", n.imu.accel_random_walk);
      break;
    case SensorType::kDvl:
      r.reject_unknown({"velocity_sigma_rel", "bias_random_walk_rel"});
      n.dvl.velocity_sigma_rel =
          optional_positive(r, "velocity_sigma_rel", n.dvl.velocity_sigma_rel);
      n.dvl.bias_random_walk_rel =
          optional_positive(r, "bias_random_walk_rel", n.dvl.bias_random_walk_rel);
      break;
    case SensorType::kDvlRanges:
      r.reject_unknown({"range_sigma"});
      n.dvl_ranges.range_sigma = optional_positive(r, "range_sigma", n.dvl_ranges.range_sigma);
      break;
    case SensorType::kLidar:
    case SensorType::kSonar:
      r.reject_unknown({"range_sigma"});
      n.range.range_sigma = optional_positive(r, "range_sigma", n.range.range_sigma);
      break;
    case SensorType::kCamera:
      r.reject_unknown({"pixel_sigma"});
      n.camera.pixel_sigma = optional_positive(r, "pixel_sigma", n.camera.pixel_sigma);
      break;
    case SensorType::kDepth:
      // Pressure depth (`file`) has depth_sigma; depth-camera frames (`scans`) range_sigma.
      r.reject_unknown({"depth_sigma", "range_sigma"});
      n.depth.depth_sigma = optional_positive(r, "depth_sigma", n.depth.depth_sigma);
      n.range.range_sigma = optional_positive(r, "range_sigma", n.range.range_sigma);
      break;
    case SensorType::kServo:
      r.reject_unknown({"angle_sigma"});
      n.servo.angle_sigma = optional_positive(r, "angle_sigma", n.servo.angle_sigma);
      break;
    case SensorType::kGnss:
      r.reject_unknown({"horizontal_sigma_m", "vertical_sigma_m"});
      n.gnss.horizontal_sigma_m =
          optional_positive(r, "horizontal_sigma_m", n.gnss.horizontal_sigma_m);
      n.gnss.vertical_sigma_m = optional_positive(r, "vertical_sigma_m", n.gnss.vertical_sigma_m);
      break;
  }
}

nlohmann::json noise_to_json(const SensorSpec& s) {
  const SensorNoise& n = s.noise;
  switch (s.type) {
    case SensorType::kImu:
      return {{"gyro_noise_density", n.imu.gyro_noise_density},
              {"accel_noise_density", n.imu.accel_noise_density},
              {"gyro_random_walk", n.imu.gyro_random_walk},
              {"accel_random_walk", n.imu.accel_random_walk}};
    case SensorType::kDvl:
      return {{"velocity_sigma_rel", n.dvl.velocity_sigma_rel},
              {"bias_random_walk_rel", n.dvl.bias_random_walk_rel}};
    case SensorType::kDvlRanges:
      return {{"range_sigma", n.dvl_ranges.range_sigma}};
    case SensorType::kLidar:
    case SensorType::kSonar:
      return {{"range_sigma", n.range.range_sigma}};
    case SensorType::kCamera:
      return {{"pixel_sigma", n.camera.pixel_sigma}};
    case SensorType::kDepth:
      return {{"depth_sigma", n.depth.depth_sigma}, {"range_sigma", n.range.range_sigma}};
    case SensorType::kServo:
      return {{"angle_sigma", n.servo.angle_sigma}};
    case SensorType::kGnss:
      return {{"horizontal_sigma_m", n.gnss.horizontal_sigma_m},
              {"vertical_sigma_m", n.gnss.vertical_sigma_m}};
  }
  return nlohmann::json::object();
}

// Which of file/scans/images fits a type: the source rules of docs/mission-format.md.
void check_source(const SensorSpec& s, const FieldReader& r) {
  const int sources = !s.file.empty() + !s.scans.empty() + !s.images.empty() + !s.topic.empty();
  if (sources != 1)
    throw ContractError(r.path() + ": expected exactly one of file, scans, images, topic; got " +
                        std::to_string(sources));
  const std::string type = to_string(s.type);
  if (!s.file.empty() && (s.type == SensorType::kLidar || s.type == SensorType::kSonar ||
                          s.type == SensorType::kCamera))
    throw ContractError(r.child("file") + ": a " + type + " sensor takes `" +
                        (s.type == SensorType::kCamera ? "images" : "scans") + ":` (a folder)");
  if (!s.scans.empty() && !is_scan_type(s.type))
    throw ContractError(r.child("scans") + ": a " + type +
                        " sensor has no scans (scans: lidar, sonar, depth)");
  if (!s.images.empty() && s.type != SensorType::kCamera)
    throw ContractError(r.child("images") + ": only camera sensors take images");
  if (!s.file.empty() && s.type == SensorType::kGnss) return;
  if (!s.topic.empty() && (s.type == SensorType::kDvlRanges || s.type == SensorType::kServo))
    throw ContractError(r.child("topic") + ": a " + type +
                        " sensor has no ROS message mapping; give `file:` (CSV)");
}

}  // namespace

std::string to_string(SensorType type) { return name_of(kSensorTypeNames, type); }
std::string known_lidar_packet_models() {
  std::string out;
  for (const char* m : kLidarPacketModels) out += (out.empty() ? "" : ", ") + std::string(m);
  return out;
}
std::string known_sensor_types() { return names_of(kSensorTypeNames); }
SensorType sensor_type_from_string(std::string_view text, const std::string& path) {
  return parse_enum(kSensorTypeNames, nlohmann::json(std::string(text)), path, "sensor type");
}
std::string to_string(TimeUnit unit) { return name_of(kUnitNames, unit); }
std::string to_string(TimeReference reference) { return name_of(kReferenceNames, reference); }
std::string to_string(Platform platform) { return name_of(kPlatformNames, platform); }

double seconds_per_unit(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::kSeconds:
      return 1.0;
    case TimeUnit::kMilliseconds:
      return 1e-3;
    case TimeUnit::kMicroseconds:
      return 1e-6;
    case TimeUnit::kNanoseconds:
      return 1e-9;
  }
  return 1.0;
}

nlohmann::json Extrinsic::to_json() const {
  return {{"translation", translation}, {"rotation_xyzw", rotation_xyzw}};
}

Extrinsic Extrinsic::from_json(const nlohmann::json& value, const std::string& path) {
  FieldReader r(value, path);
  r.reject_unknown({"translation", "rotation_xyzw"});
  Extrinsic e;
  e.translation = fixed_numbers<3>(r.at("translation"), r.child("translation"));
  e.rotation_xyzw = fixed_numbers<4>(r.at("rotation_xyzw"), r.child("rotation_xyzw"));
  const auto& q = e.rotation_xyzw;
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (std::abs(norm - 1.0) > 1e-3)
    throw ContractError(r.child("rotation_xyzw") +
                        ": expected a unit quaternion, |q| = " + std::to_string(norm));
  for (double& c : e.rotation_xyzw) c /= norm;
  return e;
}

nlohmann::json PointTimeSpec::to_json() const {
  nlohmann::json j = {{"field", field}, {"unit", to_string(unit)}};
  if (is_split()) j = {{"field", {field, nsec_field}}};
  j["reference"] = to_string(reference);
  return j;
}

PointTimeSpec PointTimeSpec::from_json(const nlohmann::json& value, const std::string& path) {
  FieldReader r(value, path);
  r.reject_unknown({"field", "unit", "reference"});
  PointTimeSpec p;
  const nlohmann::json& field = r.at("field");
  if (field.is_array()) {
    // Split time: [seconds field, nanoseconds field], both integers; the unit is implied.
    if (field.size() != 2 || !field[0].is_string() || !field[1].is_string())
      throw ContractError(r.child("field") +
                          ": expected a field name or [seconds field, nanoseconds field]");
    p.field = field[0].get<std::string>();
    p.nsec_field = field[1].get<std::string>();
    if (p.field.empty() || p.nsec_field.empty() || p.field == p.nsec_field)
      throw ContractError(r.child("field") + ": expected two different field names");
    if (r.has("unit"))
      throw ContractError(r.child("unit") +
                          ": a split time is whole seconds and nanoseconds; give no unit");
  } else {
    p.field = r.required<std::string>("field");
    if (p.field.empty()) throw ContractError(r.child("field") + ": expected a field name");
    p.unit = parse_enum(kUnitNames, r.at("unit"), r.child("unit"), "time unit");
  }
  if (r.has("reference"))
    p.reference =
        parse_enum(kReferenceNames, r.at("reference"), r.child("reference"), "time reference");
  return p;
}

nlohmann::json LidarPacketSpec::to_json() const {
  nlohmann::json j = {{"model", model}};
  if (!calibration.empty()) j["calibration"] = calibration;
  return j;
}

LidarPacketSpec LidarPacketSpec::from_json(const nlohmann::json& value, const std::string& path) {
  FieldReader r(value, path);
  r.reject_unknown({"model", "calibration"});
  LidarPacketSpec p;
  p.model = r.required<std::string>("model");
  bool known = false;
  for (const char* m : kLidarPacketModels) known = known || p.model == m;
  if (!known)
    throw ContractError(r.child("model") + ": unknown lidar packet model '" + p.model +
                        "' (known: " + known_lidar_packet_models() + ")");
  p.calibration = r.optional<std::string>("calibration", "");
  return p;
}

nlohmann::json GeoOrigin::to_json() const {
  return {{"latitude_deg", latitude_deg}, {"longitude_deg", longitude_deg}, {"height_m", height_m}};
}

GeoOrigin GeoOrigin::from_json(const nlohmann::json& value, const std::string& path) {
  FieldReader r(value, path);
  r.reject_unknown({"latitude_deg", "longitude_deg", "height_m"});
  GeoOrigin o;
  o.latitude_deg = finite_number(r.at("latitude_deg"), r.child("latitude_deg"));
  o.longitude_deg = finite_number(r.at("longitude_deg"), r.child("longitude_deg"));
  o.height_m = finite_number(r.at("height_m"), r.child("height_m"));
  if (!(std::abs(o.latitude_deg) <= 90.0))
    throw ContractError(r.child("latitude_deg") + ": expected degrees in [-90, 90]");
  if (!(std::abs(o.longitude_deg) <= 180.0))
    throw ContractError(r.child("longitude_deg") + ": expected degrees in [-180, 180]");
  return o;
}

nlohmann::json CameraSpec::to_json() const {
  return {{"model", name_of(kCameraModelNames, model)},
          {"width", width},
          {"height", height},
          {"fx", fx},
          {"fy", fy},
          {"cx", cx},
          {"cy", cy},
          {"distortion", distortion}};
}

CameraSpec CameraSpec::from_json(const nlohmann::json& value, const std::string& path) {
  FieldReader r(value, path);
  r.reject_unknown({"model", "width", "height", "fx", "fy", "cx", "cy", "distortion"});
  CameraSpec c;
  c.model = parse_enum(kCameraModelNames, r.at("model"), r.child("model"), "camera model");
  c.width = r.required<int>("width");
  c.height = r.required<int>("height");
  if (c.width <= 0 || c.height <= 0 || c.width > 100000 || c.height > 100000)
    throw ContractError(r.child("width") + ": expected image size in (0, 100000] pixels, got " +
                        std::to_string(c.width) + "x" + std::to_string(c.height));
  c.fx = positive_number(r, "fx");
  c.fy = positive_number(r, "fy");
  c.cx = finite_number(r.at("cx"), r.child("cx"));
  c.cy = finite_number(r.at("cy"), r.child("cy"));
  if (r.has("distortion")) c.distortion = numbers(r.at("distortion"), r.child("distortion"));
  const size_t n = c.distortion.size();
  if (c.model == CameraModel::kPinhole && n != 0 && n != 4)
    throw ContractError(r.child("distortion") + ": pinhole expects [] or [k1, k2, p1, p2], got " +
                        std::to_string(n) + " numbers");
  if (c.model == CameraModel::kKannalaBrandt && n != 4)
    throw ContractError(r.child("distortion") + ": kannala_brandt expects [k1, k2, k3, k4], got " +
                        std::to_string(n) + " numbers");
  return c;
}

bool SensorSpec::is_scans() const {
  return !scans.empty() || (!topic.empty() && is_scan_type(type));
}

bool SensorSpec::is_images() const {
  return !images.empty() || (!topic.empty() && type == SensorType::kCamera);
}

nlohmann::json SensorSpec::to_json() const {
  nlohmann::json j = {{"name", name}, {"type", to_string(type)}, {"rate_hz", rate_hz}};
  if (!file.empty()) j["file"] = file;
  if (!scans.empty()) j["scans"] = scans;
  if (!images.empty()) j["images"] = images;
  if (!topic.empty()) j["topic"] = topic;
  if (!frame_id.empty()) j["frame_id"] = frame_id;
  if (T_body_sensor) j["T_body_sensor"] = T_body_sensor->to_json();
  j["noise"] = noise_to_json(*this);
  if (point_time) j["point_time"] = point_time->to_json();
  if (packets) j["packets"] = packets->to_json();
  if (range_m) j["range_m"] = *range_m;
  if (!beams.empty()) j["beams"] = beams;
  if (camera) j["camera"] = camera->to_json();
  if (axis) j["axis"] = *axis;
  if (!mounted_on.empty()) j["mounted_on"] = mounted_on;
  return j;
}

SensorSpec SensorSpec::from_json(const nlohmann::json& value, const std::string& path) {
  static const std::regex kNamePattern("[A-Za-z0-9_]+");
  FieldReader r(value, path);
  r.reject_unknown({"name", "type", "file", "scans", "images", "topic", "frame_id", "rate_hz",
                    "T_body_sensor", "noise", "point_time", "packets", "range_m", "beams", "camera",
                    "axis", "mounted_on"});
  SensorSpec s;
  s.name = r.required<std::string>("name");
  check_name(s.name, r.child("name"), "[A-Za-z0-9_]+", kNamePattern);
  s.type = parse_enum(kSensorTypeNames, r.at("type"), r.child("type"), "sensor type");
  s.file = r.optional<std::string>("file", "");
  s.scans = r.optional<std::string>("scans", "");
  s.images = r.optional<std::string>("images", "");
  s.topic = r.optional<std::string>("topic", "");
  s.frame_id = r.optional<std::string>("frame_id", "");
  check_source(s, r);
  s.rate_hz = positive_number(r, "rate_hz");
  if (r.has("T_body_sensor"))
    s.T_body_sensor = Extrinsic::from_json(r.at("T_body_sensor"), r.child("T_body_sensor"));
  read_noise(r, s);
  if (r.has("point_time")) {
    if (!s.is_scans())
      throw ContractError(r.child("point_time") + ": only scan sensors have per-point time");
    s.point_time = PointTimeSpec::from_json(r.at("point_time"), r.child("point_time"));
  }
  if (r.has("packets")) {
    if (s.type != SensorType::kLidar || s.topic.empty())
      throw ContractError(r.child("packets") + ": only a lidar on a bag topic has raw packets");
    s.packets = LidarPacketSpec::from_json(r.at("packets"), r.child("packets"));
  }
  if (r.has("range_m")) {
    if (!s.is_scans() && s.type != SensorType::kDvlRanges)
      throw ContractError(r.child("range_m") + ": only scan sensors and dvl_ranges have a range");
    s.range_m = fixed_numbers<2>(r.at("range_m"), r.child("range_m"));
    if (!((*s.range_m)[0] >= 0.0 && (*s.range_m)[0] < (*s.range_m)[1]))
      throw ContractError(r.child("range_m") + ": expected [min, max] with 0 <= min < max");
  }
  if (s.type == SensorType::kDvlRanges) {
    const std::string beams_path = r.child("beams");
    const nlohmann::json& beams = r.at("beams");
    if (!beams.is_array() || beams.size() != 4)
      throw ContractError(beams_path + ": expected 4 beam directions (unit vectors)");
    for (size_t i = 0; i < 4; ++i) {
      const std::string item = beams_path + "[" + std::to_string(i) + "]";
      const auto b = fixed_numbers<3>(beams[i], item);
      const double norm = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
      if (std::abs(norm - 1.0) > 1e-3)
        throw ContractError(item + ": expected a unit vector, |b| = " + std::to_string(norm));
      s.beams.push_back({b[0] / norm, b[1] / norm, b[2] / norm});
    }
  } else if (r.has("beams")) {
    throw ContractError(r.child("beams") + ": only dvl_ranges sensors have beams");
  }
  if (s.type == SensorType::kCamera) {
    s.camera = CameraSpec::from_json(r.at("camera"), r.child("camera"));
  } else if (r.has("camera")) {
    throw ContractError(r.child("camera") + ": only camera sensors have intrinsics");
  }
  if (r.has("axis")) {
    if (s.type != SensorType::kServo)
      throw ContractError(r.child("axis") + ": only servo sensors have a rotation axis");
    const auto a = fixed_numbers<3>(r.at("axis"), r.child("axis"));
    const double norm = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (std::abs(norm - 1.0) > 1e-3)
      throw ContractError(r.child("axis") +
                          ": expected a unit vector, |a| = " + std::to_string(norm));
    s.axis = std::array<double, 3>{a[0] / norm, a[1] / norm, a[2] / norm};
  }
  s.mounted_on = r.optional<std::string>("mounted_on", "");
  if (!s.mounted_on.empty() && s.type == SensorType::kServo)
    throw ContractError(r.child("mounted_on") + ": a servo cannot ride another servo");
  return s;
}

nlohmann::json TrajectorySpec::to_json() const {
  if (!topic.empty()) return {{"topic", topic}};
  return file;
}

TrajectorySpec TrajectorySpec::from_json(const nlohmann::json& value, const std::string& path) {
  TrajectorySpec t;
  if (value.is_string()) {
    t.file = value.get<std::string>();
    if (t.file.empty()) throw ContractError(path + ": expected a file name");
    return t;
  }
  if (!value.is_object())
    throw ContractError(path + ": expected a TUM file name or {topic: ...}, got " +
                        json_type_name(value));
  FieldReader r(value, path);
  r.reject_unknown({"topic"});
  t.topic = r.required<std::string>("topic");
  if (t.topic.empty()) throw ContractError(r.child("topic") + ": expected a topic name");
  return t;
}

const SensorSpec* MissionManifest::find_sensor(std::string_view sensor_name) const {
  for (const auto& s : sensors)
    if (s.name == sensor_name) return &s;
  return nullptr;
}

const SensorSpec& MissionManifest::sensor(std::string_view sensor_name) const {
  if (const SensorSpec* s = find_sensor(sensor_name)) return *s;
  std::string known;
  for (const auto& s : sensors) known += (known.empty() ? "" : ", ") + s.name;
  throw std::out_of_range("mission '" + name + "' has no sensor '" + std::string(sensor_name) +
                          "' (sensors: " + known + ")");
}

nlohmann::json MissionManifest::to_json() const {
  nlohmann::json j = {{"keel_mission", keel_mission},
                      {"name", name},
                      {"platform", to_string(platform)},
                      {"body_frame", body_frame},
                      {"world_frame", world_frame}};
  if (origin) j["origin"] = origin->to_json();
  if (!bag.empty()) j["bag"] = bag;
  j["sensors"] = nlohmann::json::array();
  for (const auto& s : sensors) j["sensors"].push_back(s.to_json());
  if (!trajectories.empty()) {
    j["trajectories"] = nlohmann::json::object();
    for (const auto& [n, t] : trajectories) j["trajectories"][n] = t.to_json();
  }
  if (!loop_closures.empty()) j["loop_closures"] = loop_closures;
  if (!ground_truth.empty()) j["ground_truth"] = ground_truth;
  if (!cad_mesh.empty()) j["cad_mesh"] = cad_mesh;
  return j;
}

MissionManifest MissionManifest::from_json(const nlohmann::json& value, const std::string& path) {
  static const std::regex kMissionName("[A-Za-z0-9._-]+");
  FieldReader r(value, path);
  r.reject_unknown({"keel_mission", "name", "platform", "body_frame", "world_frame", "origin",
                    "bag", "sensors", "trajectories", "loop_closures", "ground_truth", "cad_mesh"});
  MissionManifest m;
  m.keel_mission = r.required<int>("keel_mission");
  if (m.keel_mission != kMissionFormatVersion)
    throw ContractError(r.child("keel_mission") + ": unsupported format version " +
                        std::to_string(m.keel_mission) + " (known: 1)");
  m.name = r.required<std::string>("name");
  check_name(m.name, r.child("name"), "[A-Za-z0-9._-]+", kMissionName);
  if (r.has("platform"))
    m.platform = parse_enum(kPlatformNames, r.at("platform"), r.child("platform"), "platform");
  m.body_frame = r.optional<std::string>("body_frame", m.body_frame);
  m.world_frame = r.optional<std::string>("world_frame", m.world_frame);
  if (r.has("origin")) m.origin = GeoOrigin::from_json(r.at("origin"), r.child("origin"));
  m.bag = r.optional<std::string>("bag", "");

  const nlohmann::json& sensors = r.at("sensors");
  if (!sensors.is_array() || sensors.empty())
    throw ContractError(r.child("sensors") + ": expected a list of at least one sensor");
  for (size_t i = 0; i < sensors.size(); ++i) {
    const std::string item = r.child("sensors") + "[" + std::to_string(i) + "]";
    SensorSpec s = SensorSpec::from_json(sensors[i], item);
    if (m.find_sensor(s.name))
      throw ContractError(item + ".name: sensor '" + s.name + "' repeated");
    if (!s.topic.empty() && m.bag.empty())
      throw ContractError(item + ".topic: a topic needs `bag:` at the top level");
    if (s.type == SensorType::kGnss && !m.origin)
      throw ContractError(item +
                          ": a gnss sensor needs `origin:` (latitude_deg, longitude_deg, "
                          "height_m of the world frame) at the top level");
    m.sensors.push_back(std::move(s));
  }
  // A tray sensor must name a servo of this mission (checked once all sensors are known).
  for (size_t i = 0; i < m.sensors.size(); ++i) {
    const SensorSpec& s = m.sensors[i];
    if (s.mounted_on.empty()) continue;
    const SensorSpec* servo = m.find_sensor(s.mounted_on);
    if (!servo || servo->type != SensorType::kServo)
      throw ContractError(r.child("sensors") + "[" + std::to_string(i) + "].mounted_on: '" +
                          s.mounted_on + "' is not a servo sensor of this mission");
  }

  if (r.has("trajectories")) {
    FieldReader t(r.at("trajectories"), r.child("trajectories"));
    t.reject_unknown({"map", "odometry", "ground_truth"});
    for (const char* name : kTrajectoryNames) {
      if (!t.has(name)) continue;
      TrajectorySpec spec = TrajectorySpec::from_json(t.at(name), t.child(name));
      if (!spec.topic.empty() && m.bag.empty())
        throw ContractError(t.child(name) + ".topic: a topic needs `bag:` at the top level");
      m.trajectories[name] = spec;
    }
  }
  m.loop_closures = r.optional<std::string>("loop_closures", "");
  m.ground_truth = r.optional<std::string>("ground_truth", "");
  m.cad_mesh = r.optional<std::string>("cad_mesh", "");
  return m;
}

}  // namespace keel::proto
