// Stage `map` on a short keel-sim usv-bridge mission (lidar_h, lidar_v, sonar): with the true
// trajectory as the refined poses the maps lie on the simulated scene (its closed-form
// distance function is the oracle), the inspection map is denser than the SLAM map, the Draco
// error reported is the decoded-vs-original one, an Ouster-style uint32 nanosecond time field
// gives the same map as Velodyne float seconds, tray sensors are skipped with a reason, and
// option errors name the option.
#include "worker/stages/map/stage.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <unordered_map>

#include "tests/error_of.h"
#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"
#include "tests/worker/io/pnts_reader.h"
#include "tests/worker/pipeline/sim_mission.h"
#include "tests/worker/pipeline/stage_run.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/folder_index.h"
#include "worker/io/tum.h"
#include "worker/stages/refine/stage.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr uint64_t kSeed = 7;

fs::path temp_root() {
  return fs::temp_directory_path() / ("keel_map_stage_" + std::to_string(::getpid()));
}

// One short simulated mission, shared by the tests of this file.
fs::path simulated_mission() {
  const fs::path dir = temp_root() / "bridge";
  if (fs::exists(dir / "mission.yaml")) return dir;
  return testing::simulate(dir, "usv-bridge", kSeed, 25.0, {"lidar_h", "lidar_v", "sonar"});
}

using testing::StageRun;

StageRun run_stage(const fs::path& mission, const json& options, const fs::path& work_dir) {
  return testing::run_stage(*make_map_stage(), mission, options, work_dir);
}

std::string error_of(const fs::path& mission, const json& options) {
  return keel::testing::error_of([&] { run_stage(mission, options, temp_root() / "work_error"); });
}

// Nearest-neighbour distances by a hash grid of cell `cell_m` (oracle for small distances:
// a neighbour farther than cell_m may be missed and then counts as +inf).
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector3f>& points, double cell_m) : cell_m_(cell_m) {
    for (const auto& p : points) cells_[key(cell_of(p))].push_back(p);
  }
  double nearest(const Eigen::Vector3f& p) const {
    const Eigen::Vector3i c = cell_of(p);
    double best = std::numeric_limits<double>::infinity();
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (const auto& q : it->second)
            best = std::min(best, (q.cast<double>() - p.cast<double>()).norm());
        }
    return best;
  }

 private:
  Eigen::Vector3i cell_of(const Eigen::Vector3f& p) const {
    return (p.cast<double>() / cell_m_).array().floor().cast<int>();
  }
  static int64_t key(const Eigen::Vector3i& c) {
    return (int64_t(c.x()) * 73856093) ^ (int64_t(c.y()) * 19349663) ^ (int64_t(c.z()) * 83492791);
  }
  double cell_m_;
  std::unordered_map<int64_t, std::vector<Eigen::Vector3f>> cells_;
};

class MapStageTest : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fs::remove_all(temp_root()); }
};

// The whole chain with the true trajectory given as `refine`'s output: maps on the scene.
TEST_F(MapStageTest, MapsFromTrueTrajectoryLieOnTheSceneAndBeatTheSlamMap) {
  const fs::path mission = simulated_mission();
  const fs::path work = temp_root() / "work_truth";
  fs::create_directories(work);
  fs::copy_file(mission / "ground_truth" / "trajectory.tum", work / kRefinedTrajectoryFile,
                fs::copy_options::overwrite_existing);
  const StageRun run = run_stage(mission, {{"metrics_max_points", 100000}}, work);
  const json& report = run.result.report;

  // Artifacts: Draco, its sidecar and PLY per sensor and combined.
  for (const std::string name : {"lidar_h", "lidar_v", "sonar", "combined"}) {
    EXPECT_TRUE(fs::exists(work / map_draco_file(name))) << name;
    EXPECT_TRUE(fs::exists(work / ("map_" + name + ".json"))) << name;
    EXPECT_TRUE(fs::exists(work / map_ply_file(name))) << name;
  }
  EXPECT_EQ(run.result.artifacts.size(), 16u);  // and tiles_<map>.tar
  EXPECT_EQ(report["poses"]["keyframes"]["source"], kRefinedTrajectoryFile);

  // Every scan of every sensor was fed, as the index files list them.
  for (const std::string sensor : {"lidar_h", "lidar_v", "sonar"}) {
    const auto index = io::read_folder_index(mission / sensor);
    const json& stats = report["sensors"][sensor]["stats"];
    EXPECT_EQ(stats["scans"].get<size_t>(), index.size()) << sensor;
    EXPECT_LE(stats["scans_outside_trajectory"].get<size_t>(), 1u) << sensor;
    EXPECT_GT(stats["points_out"].get<size_t>(), 1000u) << sensor;
    EXPECT_EQ(stats["scan_stage"]["filters"].size(), 3u) << sensor;  // Table IV
  }

  // Decoded maps lie on the simulated scene: >= 95 % within 5 cm of a returning surface
  // (lidar sigma 1 cm, sonar 2 cm, 2 cm voxels).
  const sim::Scenario scene = sim::make_scenario("usv-bridge", kSeed);
  ASSERT_NE(scene.analytic, nullptr);
  for (const std::string name : {"lidar_h", "lidar_v", "sonar", "combined"}) {
    const io::DracoPointCloud decoded =
        io::decode_draco_point_cloud(io::read_draco_file(work / map_draco_file(name)), name);
    ASSERT_FALSE(decoded.positions.empty()) << name;
    size_t near = 0, checked = 0;
    const size_t stride = std::max<size_t>(1, decoded.positions.size() / 20000);
    for (size_t k = 0; k < decoded.positions.size(); k += stride, ++checked)
      if (scene.analytic->distance_to_returning_surface(decoded.positions[k].cast<double>()) < 0.05)
        ++near;
    EXPECT_GE(static_cast<double>(near) / checked, 0.95) << name << ": " << near << "/" << checked;
  }

  // The Draco error reported is the decoded-vs-original one (PLY keeps the float originals).
  {
    const PointCloud original = io::read_scan_file(work / map_ply_file("combined"), 0);
    const io::DracoPointCloud decoded = io::decode_draco_point_cloud(
        io::read_draco_file(work / map_draco_file("combined")), "combined");
    ASSERT_EQ(decoded.positions.size(), original.size());
    const PointGrid grid(decoded.positions, 0.01);
    double max_error = 0.0;
    for (const auto& p : original.xyz) max_error = std::max(max_error, grid.nearest(p));
    const json& draco = report["combined"]["draco"];
    EXPECT_NEAR(draco["max_position_error_m"].get<double>(), max_error, 1e-7);
    EXPECT_LE(max_error, 1e-3);  // 18 bits on a map < 300 m across
  }

  // Table V: the inspection map of the SLAM lidar is denser than the SLAM map.
  const json& table = report["metrics"]["table_v"];
  EXPECT_EQ(table["inspection_map"], "inspection_lidar_h");
  EXPECT_TRUE(table["inspection_beats_slam"]["surface_density"].get<bool>()) << table.dump();
  const json& maps = report["metrics"]["maps"];
  EXPECT_GT(maps["inspection_lidar_h"]["surface_density_per_m2"]["mean"].get<double>(),
            maps["slam_map"]["surface_density_per_m2"]["mean"].get<double>());
  EXPECT_GT(report["slam_map"]["keyframes_used"].get<size_t>(), 10u);

  // Progress is monotone and ends at 1.
  ASSERT_FALSE(run.progress.empty());
  for (size_t k = 1; k < run.progress.size(); ++k) EXPECT_GE(run.progress[k], run.progress[k - 1]);
  EXPECT_EQ(run.progress.back(), 1.0);
}

std::vector<std::array<float, 4>> sorted_ply(const fs::path& ply) {
  const PointCloud cloud = io::read_scan_file(ply, 0);
  std::vector<std::array<float, 4>> points;
  for (size_t k = 0; k < cloud.size(); ++k)
    points.push_back({cloud.xyz[k].x(), cloud.xyz[k].y(), cloud.xyz[k].z(),
                      cloud.has_intensity() ? cloud.intensity[k] : -1.f});
  std::sort(points.begin(), points.end());
  return points;
}

// Issue 17, the maps out of core: a budget small enough to spill and split tiles gives the
// same maps, point for point, as the default one (which holds the tiles in memory); each map's
// LOD tiles hold its points once (read with the specification reader); the report gives the
// budget, the stage's peak RSS and what was spilled; a map whose Draco file would not fit the
// budget says so instead of writing it.
TEST_F(MapStageTest, ASmallBudgetSpillsAndGivesTheSameMapsAndTheirTiles) {
  const fs::path mission = simulated_mission();
  const fs::path roomy = temp_root() / "work_roomy", small = temp_root() / "work_small";
  const StageRun a = run_stage(mission, {{"metrics_max_points", 2000}}, roomy);
  const StageRun b =
      run_stage(mission, {{"metrics_max_points", 2000}, {"memory_budget_mb", 64}}, small);
  const json& memory_a = a.result.report["memory"];
  const json& memory_b = b.result.report["memory"];
  EXPECT_EQ(memory_a["budget_mb"], 2048);
  EXPECT_EQ(memory_a["bytes_spilled"], 0u);
  EXPECT_EQ(memory_b["budget_mb"], 64);
  EXPECT_GT(memory_b["bytes_spilled"].get<uint64_t>(), 10u << 20);
  EXPECT_LE(memory_b["spill_buffered_peak_mib"].get<double>(), 16.0 + 4 * 7);  // + binner batches
  EXPECT_GT(memory_b["peak_rss_mib"].get<double>(), 10.0);
  for (const std::string name : {"lidar_h", "lidar_v", "sonar", "combined"}) {
    SCOPED_TRACE(name);
    const auto points = sorted_ply(roomy / map_ply_file(name));
    EXPECT_TRUE(points == sorted_ply(small / map_ply_file(name)));
    const json& map =
        name == "combined" ? b.result.report["combined"] : b.result.report["sensors"][name]["map"];
    EXPECT_EQ(map["points"], points.size());
    // The LOD tiles: every point in exactly one finest tile.
    const keel::testing::Tileset tiles =
        keel::testing::read_tileset_tar(small / map_tiles_file(name), temp_root() / ("x_" + name));
    size_t finest = 0;
    for (const auto& [uri, tile] : tiles.tiles) {
      if (!tile.children.empty()) continue;
      finest += tile.content.positions.size();
      ASSERT_EQ(tile.content.properties.at("intensity").size(), tile.content.positions.size());
      if (name == "combined") {
        for (const double sensor : tile.content.properties.at("sensor"))
          EXPECT_TRUE(sensor == 0 || sensor == 1 || sensor == 2);
      }
    }
    EXPECT_EQ(finest, points.size());
    EXPECT_EQ(tiles.json["extras"]["keel"]["points"], points.size());
    EXPECT_EQ(map["tiles"]["points"], points.size());
    // Draco: written when it fits the budget, else said why.
    if (fs::exists(small / map_draco_file(name))) {
      EXPECT_GT(map["draco"]["bytes"].get<size_t>(), 0u);
    } else {
      EXPECT_EQ(map["draco"]["written"], false);
      EXPECT_NE(map["draco"]["reason"].get<std::string>().find("map.memory_budget_mb"),
                std::string::npos);
    }
    EXPECT_TRUE(fs::exists(roomy / map_draco_file(name)));
  }
  EXPECT_EQ(b.result.report["sensors"]["lidar_h"]["stats"]["final_stage"]["filters"][0]["filter"],
            "voxel_grid");
  const json tiles_combined =
      keel::testing::read_tileset_tar(small / map_tiles_file("combined"), temp_root() / "x_c").json;
  EXPECT_EQ(tiles_combined["extras"]["keel"]["sensors"], json({"lidar_h", "lidar_v", "sonar"}));
  // The same figures either way.
  EXPECT_EQ(a.result.report["metrics"]["maps"]["inspection_combined"]["points"],
            b.result.report["metrics"]["maps"]["inspection_combined"]["points"]);
  EXPECT_EQ(a.result.report["metrics"]["maps"]["slam_map"]["surface_density_per_m2"]["mean"],
            b.result.report["metrics"]["maps"]["slam_map"]["surface_density_per_m2"]["mean"]);
}

// A budget that cannot hold one tile, whatever the splits, is refused naming the option and the
// smallest budget that would work (here a final ROR whose 50 m halo takes in the whole map).
TEST_F(MapStageTest, ABudgetTooSmallForOneTileIsRefusedWithTheMinimum) {
  const std::string error =
      error_of(simulated_mission(),
               {{"memory_budget_mb", 64},
                {"sensors", {"lidar_h"}},
                {"lidar_filters", {{"final_filters", {{{"type", "ror"}, {"radius", 50.0}}}}}}});
  EXPECT_NE(error.find("options.map.memory_budget_mb: 64 MiB cannot hold one tile"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("the smallest budget that would work is"), std::string::npos) << error;
  EXPECT_NE(error.find("lidar_h"), std::string::npos) << error;
  const std::string below = error_of(simulated_mission(), {{"memory_budget_mb", 16}});
  EXPECT_NE(below.find("options.map.memory_budget_mb"), std::string::npos) << below;
}

// Writes a copy of the mission whose lidar_h scans carry Ouster's uint32 nanosecond field `t`.
fs::path ouster_style_copy(const fs::path& mission) {
  const fs::path dir = temp_root() / "bridge_ouster";
  fs::remove_all(dir);
  fs::create_directories(dir / "lidar_h");
  YAML::Node yaml = YAML::LoadFile((mission / "mission.yaml").string());
  YAML::Node kept(YAML::NodeType::Sequence);
  for (auto sensor : yaml["sensors"]) {
    if (sensor["name"].as<std::string>() != "lidar_h") continue;
    sensor["point_time"]["field"] = "t";
    sensor["point_time"]["unit"] = "ns";
    kept.push_back(sensor);
  }
  yaml["sensors"] = kept;
  std::ofstream(dir / "mission.yaml") << YAML::Dump(yaml);
  for (const char* file : {"map_poses.tum", "odometry.tum"})
    fs::copy_file(mission / file, dir / file);
  fs::copy(mission / "ground_truth", dir / "ground_truth", fs::copy_options::recursive);
  io::ScanReadOptions read;
  read.point_time = proto::PointTimeSpec{};  // field time, seconds, scan start
  io::ScanWriteOptions write;
  write.time =
      io::PointTimeEncoding{{"t", proto::TimeUnit::kNanoseconds, proto::TimeReference::kScanStart},
                            io::FieldType::kUint32};
  std::vector<io::IndexEntry> entries = io::read_folder_index(mission / "lidar_h");
  for (auto& entry : entries) {
    const PointCloud scan = io::read_scan_file(entry.path, entry.t_ns, read);
    EXPECT_TRUE(scan.has_time());
    entry.path = dir / "lidar_h" / entry.path.filename();
    io::write_scan_file(entry.path, scan, write);
  }
  io::write_folder_index(dir / "lidar_h", entries);
  return dir;
}

TEST_F(MapStageTest, OusterNanosecondTimeFieldGivesTheSameMap) {
  const fs::path mission = simulated_mission();
  const fs::path ouster = ouster_style_copy(mission);
  const json options = {{"sensors", {"lidar_h"}}, {"metrics_max_points", 2000}};
  const fs::path work_s = temp_root() / "work_seconds", work_ns = temp_root() / "work_ns";
  const StageRun seconds = run_stage(mission, options, work_s);
  const StageRun nanoseconds = run_stage(ouster, options, work_ns);
  const PointCloud a = io::read_scan_file(work_s / map_ply_file("lidar_h"), 0);
  const PointCloud b = io::read_scan_file(work_ns / map_ply_file("lidar_h"), 0);
  ASSERT_GT(a.size(), 1000u);
  // Times differ by < 1 ns after the unit conversion: the same voxels, the same centroids
  // (to float rounding).
  EXPECT_NEAR(static_cast<double>(b.size()), static_cast<double>(a.size()), 0.001 * a.size());
  const PointGrid grid(b.xyz, 0.01);
  size_t same = 0;
  for (const auto& p : a.xyz)
    if (grid.nearest(p) < 1e-4) ++same;
  EXPECT_GE(static_cast<double>(same) / a.size(), 0.999);
  EXPECT_EQ(seconds.result.report["sensors"]["lidar_h"]["stats"]["points_in"],
            nanoseconds.result.report["sensors"]["lidar_h"]["stats"]["points_in"]);
}

// A hand-written mission: a lidar on the body, another on a servo tray; two planar scans.
fs::path tray_mission() {
  const fs::path dir = temp_root() / "tray";
  fs::remove_all(dir);
  for (const char* sensor : {"lidar_fixed", "lidar_tray"}) {
    fs::create_directories(dir / sensor);
    std::ofstream index(dir / sensor / "index.csv");
    index << "t,file\n";
    for (int s = 0; s < 4; ++s) {
      PointCloud scan;
      for (int i = -40; i <= 40; ++i)
        for (int j = -40; j <= 40; ++j) scan.xyz.emplace_back(0.1f * i, 0.1f * j, -5.0f);
      const std::string file = "s" + std::to_string(s) + ".pcd";
      io::write_scan_file(dir / sensor / file, scan);
      index << "1700000000." << s << "," << file << "\n";
    }
  }
  std::ofstream(dir / "servo.csv") << "t,angle\n1700000000.0,0\n1700000000.5,0\n";
  std::ofstream map(dir / "map_poses.tum");
  for (int k = 0; k <= 5; ++k) map << "1700000000." << k << " " << 0.1 * k << " 0 0 0 0 0 1\n";
  std::ofstream(dir / "mission.yaml") << R"(keel_mission: 1
name: tray
platform: hauv
sensors:
  - name: servo
    type: servo
    file: servo.csv
    rate_hz: 2
    T_body_sensor: {translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 1]}
  - name: lidar_fixed
    type: lidar
    scans: lidar_fixed
    rate_hz: 10
    T_body_sensor: {translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 1]}
  - name: lidar_tray
    type: lidar
    scans: lidar_tray
    rate_hz: 10
    mounted_on: servo
    T_body_sensor: {translation: [0, 0, 0], rotation_xyzw: [0, 0, 0, 1]}
trajectories:
  map: map_poses.tum
)";
  return dir;
}

TEST_F(MapStageTest, TraySensorsAreSkippedWithTheReason) {
  const fs::path mission = tray_mission();
  // Table IV's DROR would remove this sparse synthetic grid; no scan filters here.
  const json options = {{"metrics_max_points", 1000},
                        {"lidar_filters", {{"scan_filters", json::array()}}}};
  const StageRun run = run_stage(mission, options, temp_root() / "work_tray");
  const json& report = run.result.report;
  ASSERT_EQ(report["skipped_sensors"].size(), 1u) << report["skipped_sensors"].dump();
  EXPECT_EQ(report["skipped_sensors"][0]["sensor"], "lidar_tray");
  EXPECT_NE(report["skipped_sensors"][0]["reason"].get<std::string>().find("servo"),
            std::string::npos);
  EXPECT_TRUE(report["sensors"].contains("lidar_fixed"));
  EXPECT_FALSE(report["sensors"].contains("lidar_tray"));
  // The plane at z = -5 m, 0.1 m grid, 2 cm voxels: the map is that plane, shifted by the pose.
  const PointCloud map =
      io::read_scan_file(temp_root() / "work_tray" / map_ply_file("lidar_fixed"), 0);
  ASSERT_FALSE(map.empty());
  for (const auto& p : map.xyz) EXPECT_NEAR(p.z(), -5.0f, 1e-4f);
  // No odometry: the keyframes are interpolated; every scan is inside them.
  EXPECT_EQ(report["sensors"]["lidar_fixed"]["stats"]["scans_outside_trajectory"], 0);
}

TEST_F(MapStageTest, ASensorNamedLikeTheCombinedMapIsRefused) {
  const fs::path mission = tray_mission();
  std::ifstream in(mission / "mission.yaml");
  std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string from = "- name: lidar_fixed";
  yaml.replace(yaml.find(from), from.size(), std::string("- name: ") + kCombinedMapName);
  std::ofstream(mission / "mission.yaml") << yaml;
  fs::remove_all(temp_root() / "work_error");
  const std::string error = error_of(mission, {{"metrics_max_points", 1000}});
  EXPECT_NE(error.find("reserved for the combined map"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(temp_root() / "work_error" / map_draco_file(kCombinedMapName)));
}

// The first sensor's outputs start while the second still scans; when the second then fails,
// the stage must not leave the first one's files behind looking finished.
TEST_F(MapStageTest, AFailedStageLeavesNoMapFilesBehind) {
  const fs::path mission = tray_mission();
  std::ifstream in(mission / "mission.yaml");
  std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string tray = "    mounted_on: servo\n";
  yaml.erase(yaml.find(tray), tray.size());  // lidar_tray becomes a fixed second sensor
  std::ofstream(mission / "mission.yaml") << yaml;
  const fs::path last_scan = mission / "lidar_tray" / "s3.pcd";
  fs::resize_file(last_scan, fs::file_size(last_scan) / 2);
  const fs::path work = temp_root() / "work_failed";
  fs::remove_all(work);
  const json options = {{"metrics_max_points", 1000},
                        {"lidar_filters", {{"scan_filters", json::array()}}}};
  std::string error;
  try {
    run_stage(mission, options, work);
  } catch (const std::exception& e) {
    error = e.what();
  }
  EXPECT_NE(error.find("s3.pcd"), std::string::npos) << error;
  for (const auto& entry : fs::directory_iterator(work)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name.rfind("map_", 0) != 0 && name.rfind("tiles_", 0) != 0)
        << name << " left behind";
  }
}

TEST_F(MapStageTest, OptionErrorsNameTheOption) {
  const fs::path mission = tray_mission();
  const std::string unknown = error_of(mission, {{"voxel_leaf", 0.1}});
  EXPECT_NE(unknown.find("options.map.voxel_leaf"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("final_voxel_leaf_m"), std::string::npos) << unknown;  // known ones
  const std::string chain = error_of(
      mission, {{"lidar_filters", {{"scan_filters", {{{"type", "voxel_grid"}, {"leaf", -1}}}}}}});
  EXPECT_NE(chain.find("options.map.lidar_filters.scan_filters[0].leaf"), std::string::npos)
      << chain;
  const std::string sensor = error_of(mission, {{"sensor_filters", {{"sonar9", json::object()}}}});
  EXPECT_NE(sensor.find("options.map.sensor_filters.sonar9"), std::string::npos) << sensor;
  const std::string bits = error_of(mission, {{"draco_position_bits", 31}});
  EXPECT_NE(bits.find("options.map.draco_position_bits"), std::string::npos) << bits;
  const std::string missing = error_of(mission, {{"sensors", {"lidar_nope"}}});
  EXPECT_NE(missing.find("lidar_nope"), std::string::npos) << missing;
  const std::string type = error_of(mission, {{"sensors", {"servo"}}});
  EXPECT_NE(type.find("expected a lidar or sonar"), std::string::npos) << type;
  const std::string twice = error_of(mission, {{"sensors", {"lidar_fixed", "lidar_fixed"}}});
  EXPECT_NE(twice.find("'lidar_fixed' is listed twice"), std::string::npos) << twice;
  const std::string radius = error_of(mission, {{"metrics_radius_m", 1e9}});
  EXPECT_NE(radius.find("options.map.metrics_radius_m"), std::string::npos) << radius;
  const std::string preview = error_of(mission, {{"preview_max_points", 500}});
  EXPECT_NE(preview.find("options.map.preview_max_points"), std::string::npos) << preview;
}

// Previews are what a viewer opens first where a big map has no level-of-detail tiles: none
// by default (tiles are written), 2 M points without tiles, any explicit value kept.
TEST(MapStageOptions, PreviewsByDefaultOnlyWithoutTiles) {
  EXPECT_EQ(MapStageOptions::from_json(json::object()).preview_max_points, 0u);
  EXPECT_EQ(MapStageOptions::from_json({{"write_tiles", false}}).preview_max_points,
            MapStageOptions::kDefaultPreviewPoints);
  EXPECT_EQ(MapStageOptions::from_json({{"preview_max_points", 5000}}).preview_max_points, 5000u);
  EXPECT_EQ(MapStageOptions::from_json({{"write_tiles", false}, {"preview_max_points", 0}})
                .preview_max_points,
            0u);
}

}  // namespace
}  // namespace keel::pipeline
