#include "worker/stages/calibrate/artifacts.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "core/replaced_file.h"
#include "worker/pipeline/pose_json.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;
constexpr char kMagic[8] = {'K', 'E', 'E', 'L', 'C', 'A', 'L', '1'};
constexpr size_t kHeaderBytes = 16;  // magic + uint64 index length
constexpr size_t kPointBytes = 3 * sizeof(float);

void put_u64(std::string& out, uint64_t value) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

uint64_t get_u64(const char* bytes) {
  uint64_t value = 0;
  for (int i = 7; i >= 0; --i) value = (value << 8) | static_cast<unsigned char>(bytes[i]);
  return value;
}

// The index with every block's offset; blocks follow the padded index in the order listed.
json index_json(const CalibrationScans& scans, size_t first_block_offset) {
  json sensors = json::array();
  size_t offset = first_block_offset;
  for (const auto& sensor : scans.sensors) {
    json list = json::array();
    for (const auto& scan : sensor.scans) {
      list.push_back({{"keyframe", scan.keyframe},
                      {"t_s", scan.t_s},
                      {"T_world_body", pose_to_json(scan.T_world_body)},
                      {"offset", offset},
                      {"count", scan.points.size()}});
      offset += scan.points.size() * kPointBytes;
    }
    sensors.push_back({{"name", sensor.name},
                       {"type", sensor.type},
                       {"T_body_sensor", pose_to_json(sensor.T_body_sensor)},
                       {"source", sensor.source},
                       {"scans", std::move(list)}});
  }
  json keyframes = json::array();
  for (double t : scans.keyframes_t_s) keyframes.push_back({{"t_s", t}});
  return {{"format", "keel-calibration-scans"}, {"version", 1},
          {"reference", scans.reference},       {"t0_s", scans.t0_s},
          {"keyframes", std::move(keyframes)},  {"sensors", std::move(sensors)}};
}

// The index's text, padded with spaces so the blocks start 4-byte aligned. The offsets it
// holds depend on its own length, so it is serialised until that length is stable.
std::string padded_index(const CalibrationScans& scans) {
  size_t length = 0;
  for (;;) {
    std::string text = index_json(scans, kHeaderBytes + length).dump();
    const size_t padded = (kHeaderBytes + text.size() + 3) / 4 * 4 - kHeaderBytes;
    if (padded == length) {
      text.append(padded - text.size(), ' ');
      return text;
    }
    length = padded;
  }
}

}  // namespace

void write_calibration_scans(const std::filesystem::path& path, const CalibrationScans& scans) {
  const std::string index = padded_index(scans);
  std::string header(kMagic, sizeof kMagic);
  put_u64(header, index.size());
  ReplacedFile file(path);
  file.append(header.data(), header.size());
  file.append(index.data(), index.size());
  static_assert(sizeof(Eigen::Vector3f) == kPointBytes, "points are written as packed float32");
  for (const auto& sensor : scans.sensors)
    for (const auto& scan : sensor.scans)
      file.append(reinterpret_cast<const char*>(scan.points.data()),
                  scan.points.size() * kPointBytes);
  file.commit();
}

CalibrationScans read_calibration_scans(const std::filesystem::path& path) {
  const std::string where = path.string() + ": ";
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(where + "cannot be opened");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw std::runtime_error(where + "not a calibration scans file (magic KEELCAL1 expected)");
  const uint64_t index_length = get_u64(bytes.data() + 8);
  if (index_length > bytes.size() - kHeaderBytes)
    throw std::runtime_error(where + "index of " + std::to_string(index_length) +
                             " bytes runs past the end of the file");
  const json index = json::parse(bytes.substr(kHeaderBytes, index_length), nullptr, false);
  if (index.is_discarded() || !index.is_object() || index.value("version", 0) != 1)
    throw std::runtime_error(where + "index is not version-1 JSON");
  CalibrationScans scans;
  try {
    scans.reference = index.at("reference").get<std::string>();
    scans.t0_s = index.at("t0_s").get<double>();
    for (const auto& k : index.at("keyframes")) scans.keyframes_t_s.push_back(k.at("t_s"));
    for (const auto& s : index.at("sensors")) {
      CalibrationSensorScans sensor;
      sensor.name = s.at("name").get<std::string>();
      sensor.type = s.at("type").get<std::string>();
      sensor.source = s.at("source").get<std::string>();
      sensor.T_body_sensor = pose_from_json(s.at("T_body_sensor"), sensor.name + ".T_body_sensor");
      for (const auto& item : s.at("scans")) {
        CalibrationScan scan;
        scan.keyframe = item.at("keyframe").get<size_t>();
        scan.t_s = item.at("t_s").get<double>();
        scan.T_world_body = pose_from_json(item.at("T_world_body"), sensor.name + ".T_world_body");
        const uint64_t offset = item.at("offset").get<uint64_t>();
        const uint64_t count = item.at("count").get<uint64_t>();
        if (scan.keyframe >= scans.keyframes_t_s.size() || offset % 4 != 0 ||
            offset < kHeaderBytes + index_length || offset > bytes.size() ||
            count > (bytes.size() - offset) / kPointBytes)
          throw std::runtime_error("scan at keyframe " + std::to_string(scan.keyframe) + " of " +
                                   sensor.name + ": block out of bounds or misaligned");
        scan.points.resize(count);
        std::memcpy(scan.points.data(), bytes.data() + offset, count * kPointBytes);
        sensor.scans.push_back(std::move(scan));
      }
      scans.sensors.push_back(std::move(sensor));
    }
  } catch (const json::exception& e) {
    throw std::runtime_error(where + "index: " + e.what());
  } catch (const std::exception& e) {
    throw std::runtime_error(where + e.what());
  }
  return scans;
}

}  // namespace keel::pipeline
