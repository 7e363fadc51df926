#include "worker/io/lidar/velodyne_calibration.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

#include "worker/io/io_error.h"

namespace keel::io::lidar {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

// Elevations (deg) by laser_id: VLP-16 manual Table 9-1; VLP-32C manual Table 9-1; HDL-32E
// manual, "Laser firing order" table.
constexpr std::array<double, 16> kVlp16Vert = {-15, 1, -13, 3,  -11, 5,  -9, 7,
                                               -7,  9, -5,  11, -3,  13, -1, 15};
constexpr std::array<double, 32> kVlp32cVert = {
    -25,    -1,     -1.667, -15.639, -11.31, 0,      -0.667, -8.843, -7.254, 0.333,  -0.333,
    -6.148, -5.333, 1.333,  0.667,   -4,     -4.667, 1.667,  1,      -3.667, -3.333, 3.333,
    2.333,  -2.667, -3,     7,       4.667,  -2.333, -2,     15,     10.333, -1.333};
// VLP-32C azimuth offsets (deg) as the drivers' rot_correction: the manual's offset negated.
constexpr std::array<double, 32> kVlp32cRot = {
    -1.4, 4.2, -1.4, 1.4, -1.4, 1.4, -4.2, 1.4, -1.4, 4.2, -1.4, 1.4, -4.2, 1.4, -4.2, 1.4,
    -1.4, 4.2, -1.4, 4.2, -4.2, 1.4, -1.4, 1.4, -1.4, 1.4, -1.4, 4.2, -4.2, 1.4, -1.4, 1.4};
constexpr std::array<double, 32> kHdl32eVert = {
    -30.67, -9.33,  -29.33, -8.00,  -28.00, -6.67,  -26.67, -5.33,  -25.33, -4.00,  -24.00,
    -2.67,  -22.67, -1.33,  -21.33, 0.00,   -20.00, 1.33,   -18.67, 2.67,   -17.33, 4.00,
    -16.00, 5.33,   -14.67, 6.67,   -13.33, 8.00,   -12.00, 9.33,   -10.67, 10.67};

double distance_resolution(VelodyneModel model) {
  // VLP-32C reports distance in 4 mm units, the others in 2 mm (user manuals, "Data Point").
  return model == VelodyneModel::kVlp32c ? 0.004 : 0.002;
}

YAML::Node required(const YAML::Node& node, const char* key, const std::string& where) {
  const YAML::Node value = node[key];
  if (!value) throw IoError(where + ": missing field '" + key + "'");
  return value;
}

double number(const YAML::Node& node, const char* key, const std::string& where, double fallback,
              bool is_required) {
  const YAML::Node value = node[key];
  if (!value) {
    if (is_required) throw IoError(where + ": missing field '" + key + "'");
    return fallback;
  }
  double result = 0.0;
  try {
    result = value.as<double>();
  } catch (const YAML::Exception&) {
    throw IoError(where + ": field '" + key + "' is not a number");
  }
  if (!std::isfinite(result)) throw IoError(where + ": field '" + key + "' is not finite");
  return result;
}

}  // namespace

VelodyneModel velodyne_model_from_string(std::string_view name, const std::string& path) {
  if (name == "VLP16") return VelodyneModel::kVlp16;
  if (name == "VLP32C") return VelodyneModel::kVlp32c;
  if (name == "HDL32E") return VelodyneModel::kHdl32e;
  throw IoError(path + ": unknown Velodyne model '" + std::string(name) +
                "' (known: VLP16, VLP32C, HDL32E)");
}

std::string to_string(VelodyneModel model) {
  switch (model) {
    case VelodyneModel::kVlp16:
      return "VLP16";
    case VelodyneModel::kVlp32c:
      return "VLP32C";
    case VelodyneModel::kHdl32e:
      return "HDL32E";
  }
  return "?";
}

size_t laser_count(VelodyneModel model) { return model == VelodyneModel::kVlp16 ? 16 : 32; }

uint8_t product_id(VelodyneModel model) {
  switch (model) {
    case VelodyneModel::kVlp16:
      return 0x22;
    case VelodyneModel::kVlp32c:
      return 0x28;
    case VelodyneModel::kHdl32e:
      return 0x21;
  }
  return 0;
}

void VelodyneCalibration::finalise() {
  for (VelodyneLaser& laser : lasers) {
    laser.cos_vert = static_cast<float>(std::cos(laser.vert_rad));
    laser.sin_vert = static_cast<float>(std::sin(laser.vert_rad));
    laser.cos_rot = static_cast<float>(std::cos(laser.rot_rad));
    laser.sin_rot = static_cast<float>(std::sin(laser.rot_rad));
  }
  // Rings count upwards by elevation (ties keep laser_id order), as the drivers number them.
  std::vector<size_t> order(lasers.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return lasers[a].vert_rad < lasers[b].vert_rad; });
  for (size_t rank = 0; rank < order.size(); ++rank)
    lasers[order[rank]].ring = static_cast<uint16_t>(rank);
}

VelodyneCalibration factory_calibration(VelodyneModel model) {
  VelodyneCalibration calibration;
  calibration.model = model;
  calibration.distance_resolution_m = distance_resolution(model);
  calibration.lasers.resize(laser_count(model));
  for (size_t i = 0; i < calibration.lasers.size(); ++i) {
    VelodyneLaser& laser = calibration.lasers[i];
    switch (model) {
      case VelodyneModel::kVlp16:
        laser.vert_rad = kVlp16Vert[i] * kDegToRad;
        break;
      case VelodyneModel::kVlp32c:
        laser.vert_rad = kVlp32cVert[i] * kDegToRad;
        laser.rot_rad = kVlp32cRot[i] * kDegToRad;
        break;
      case VelodyneModel::kHdl32e:
        laser.vert_rad = kHdl32eVert[i] * kDegToRad;
        break;
    }
  }
  calibration.finalise();
  return calibration;
}

VelodyneCalibration parse_velodyne_calibration(const std::string& yaml_text, VelodyneModel model,
                                               const std::string& name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw IoError(name + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap()) throw IoError(name + ": expected a map with 'lasers'");
  VelodyneCalibration calibration;
  calibration.model = model;
  const size_t count = laser_count(model);
  calibration.distance_resolution_m =
      number(root, "distance_resolution", name, distance_resolution(model), false);
  if (!(calibration.distance_resolution_m > 0.0 && calibration.distance_resolution_m < 1.0))
    throw IoError(name + ": field 'distance_resolution' must be in (0, 1) m");
  if (root["num_lasers"]) {
    const double n = number(root, "num_lasers", name, 0, true);
    if (n != static_cast<double>(count))
      throw IoError(name + ": num_lasers is " + std::to_string(static_cast<long>(n)) + "; a " +
                    to_string(model) + " has " + std::to_string(count));
  }
  const YAML::Node lasers = required(root, "lasers", name);
  if (!lasers.IsSequence() || lasers.size() != count)
    throw IoError(name + ": 'lasers' must list " + std::to_string(count) + " lasers for a " +
                  to_string(model));
  calibration.lasers.resize(count);
  std::vector<bool> seen(count, false);
  for (size_t i = 0; i < count; ++i) {
    const YAML::Node entry = lasers[i];
    const std::string where = name + ": lasers[" + std::to_string(i) + "]";
    if (!entry.IsMap()) throw IoError(where + ": expected a map");
    const double id = number(entry, "laser_id", where, 0, true);
    if (id < 0 || id >= static_cast<double>(count) || id != std::floor(id))
      throw IoError(where + ": laser_id " + std::to_string(id) + " out of 0.." +
                    std::to_string(count - 1));
    const size_t index = static_cast<size_t>(id);
    if (seen[index]) throw IoError(where + ": laser_id " + std::to_string(index) + " repeated");
    seen[index] = true;
    if (entry["two_pt_correction_available"] &&
        entry["two_pt_correction_available"].as<std::string>() == "true")
      throw IoError(where + ": two_pt_correction_available (HDL-64E) is not supported");
    VelodyneLaser& laser = calibration.lasers[index];
    laser.vert_rad = number(entry, "vert_correction", where, 0, true);
    laser.rot_rad = number(entry, "rot_correction", where, 0, true);
    laser.dist_correction_m = number(entry, "dist_correction", where, 0, false);
    laser.vert_offset_m = number(entry, "vert_offset_correction", where, 0, false);
    laser.horiz_offset_m = number(entry, "horiz_offset_correction", where, 0, false);
    if (std::abs(laser.vert_rad) > M_PI / 2 || std::abs(laser.rot_rad) > M_PI)
      throw IoError(where + ": vert_correction / rot_correction out of range (radians expected)");
  }
  calibration.finalise();
  return calibration;
}

VelodyneCalibration load_velodyne_calibration(const std::filesystem::path& file,
                                              VelodyneModel model) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw IoError(file.string() + ": cannot open the Velodyne calibration file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_velodyne_calibration(text.str(), model, file.string());
}

}  // namespace keel::io::lidar
