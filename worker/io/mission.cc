#include "worker/io/mission.h"

#include "proto/contract_error.h"
#include "worker/io/display_path.h"
#include "worker/io/io_error.h"
#include "worker/io/yaml_json.h"

namespace keel::io {

namespace fs = std::filesystem;

namespace {

enum class Kind { kFile, kFolder, kIndexedFolder, kFileOrFolder };

class Resolver {
 public:
  Resolver(fs::path dir, std::string manifest)
      : dir_(std::move(dir)), manifest_(std::move(manifest)) {}

  fs::path resolve(const std::string& relative, const std::string& field, Kind kind) const {
    const fs::path rel(relative);
    if (rel.is_absolute() || escapes(rel))
      fail(field, "'" + relative + "' must be a relative path inside the bundle");
    const fs::path path = (dir_ / rel).lexically_normal();
    // The full path helps only when it says more than the manifest's own words (a local run;
    // a worker's copy of the bundle shows the name relative to it, as in mission.yaml).
    const std::string shown = display_path(path);
    const std::string at =
        shown == rel.lexically_normal().generic_string() ? "" : " (" + shown + ")";
    std::error_code ec;
    const auto status = fs::status(path, ec);
    if (!fs::exists(status)) fail(field, "'" + relative + "' not found" + at);
    if (kind == Kind::kFile && !fs::is_regular_file(status))
      fail(field, "'" + relative + "' is not a file" + at);
    if (kind != Kind::kFile && kind != Kind::kFileOrFolder && !fs::is_directory(status))
      fail(field, "'" + relative + "' is not a folder" + at);
    if (kind == Kind::kIndexedFolder && !fs::is_regular_file(path / "index.csv"))
      fail(field, "'" + relative + "' has no index.csv (" + display_path(path / "index.csv") + ")");
    return path;
  }

  [[noreturn]] void fail(const std::string& field, const std::string& message) const {
    throw IoError(manifest_ + ": " + field + ": " + message);
  }

 private:
  static bool escapes(const fs::path& rel) {
    int depth = 0;
    for (const auto& part : rel.lexically_normal()) {
      if (part == "..")
        --depth;
      else if (part != ".")
        ++depth;
      if (depth < 0) return true;
    }
    return false;
  }

  fs::path dir_;
  std::string manifest_;
};

}  // namespace

const fs::path& Mission::sensor_path(std::string_view name) const {
  const auto it = sensor_paths.find(std::string(name));
  if (it == sensor_paths.end())
    throw IoError(display_path(manifest_path) + ": sensor '" + std::string(name) +
                  "' has no file or folder (it reads from bag topic '" + sensor(name).topic + "')");
  return it->second;
}

Mission load_mission(const fs::path& dir_in) {
  Mission mission;
  std::error_code ec;
  mission.dir = fs::absolute(dir_in, ec).lexically_normal();
  mission.manifest_path = mission.dir / "mission.yaml";
  if (!fs::is_regular_file(mission.manifest_path))
    throw IoError(display_path(mission.manifest_path) +
                  ": not found (a mission bundle has mission.yaml at its root)");
  const std::string manifest_name = display_path(mission.manifest_path);
  const nlohmann::json document = load_yaml_file(mission.manifest_path);
  try {
    mission.manifest = proto::MissionManifest::from_json(document, "");
  } catch (const proto::ContractError& e) {
    throw IoError(manifest_name + ": " + e.what());
  }

  const Resolver resolver(mission.dir, manifest_name);
  const auto& m = mission.manifest;
  // A ROS1 .bag or a ROS 2 .mcap/.db3 file, or a rosbag2 folder (bag_source.h).
  if (!m.bag.empty()) mission.bag_path = resolver.resolve(m.bag, "bag", Kind::kFileOrFolder);
  for (size_t i = 0; i < m.sensors.size(); ++i) {
    const auto& s = m.sensors[i];
    const std::string item = "sensors[" + std::to_string(i) + "]";
    if (!s.file.empty())
      mission.sensor_paths[s.name] = resolver.resolve(s.file, item + ".file", Kind::kFile);
    if (!s.scans.empty())
      mission.sensor_paths[s.name] =
          resolver.resolve(s.scans, item + ".scans", Kind::kIndexedFolder);
    if (!s.images.empty())
      mission.sensor_paths[s.name] =
          resolver.resolve(s.images, item + ".images", Kind::kIndexedFolder);
    if (s.packets && !s.packets->calibration.empty())
      mission.calibration_paths[s.name] =
          resolver.resolve(s.packets->calibration, item + ".packets.calibration", Kind::kFile);
  }
  for (const auto& [name, t] : m.trajectories)
    if (!t.file.empty())
      mission.trajectory_paths[name] =
          resolver.resolve(t.file, "trajectories." + name, Kind::kFile);
  if (!m.loop_closures.empty())
    mission.loop_closures_path = resolver.resolve(m.loop_closures, "loop_closures", Kind::kFile);
  if (!m.ground_truth.empty())
    mission.ground_truth_path = resolver.resolve(m.ground_truth, "ground_truth", Kind::kFile);
  if (!m.cad_mesh.empty())
    mission.cad_mesh_path = resolver.resolve(m.cad_mesh, "cad_mesh", Kind::kFile);
  return mission;
}

}  // namespace keel::io
