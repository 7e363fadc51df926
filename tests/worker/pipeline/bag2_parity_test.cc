// One keel-sim mission recorded three ways (a ROS1 bag written by rosbag_storage, the reference,
// and ROS 2 bags in MCAP and SQLite3, one of them split into files with lz4 chunks): the
// ingest report, the refined trajectory and the maps must be the same from each.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/sim/simulator.h"
#include "tests/worker/pipeline/stage_run.h"
#include "worker/io/tum.h"
#include "worker/stages/ingest/stage.h"
#include "worker/stages/map/stage.h"
#include "worker/stages/refine/stage.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path temp_root() { return fs::temp_directory_path() / "keel-bag2-parity"; }

// The simulation, written once: files, mission.bag, mission_mcap/, mission_db3/ and (a second
// run of the same seed) mission_mcap/ split into ~1 MB files with lz4 chunks.
const fs::path& simulated() {
  static const fs::path dir = [] {
    fs::remove_all(temp_root());
    sim::SimOptions o;
    o.scenario = "usv-bridge";
    o.seed = 3;
    o.duration_s = 20.0;
    o.sensors = {"imu", "dvl", "lidar_h", "camera"};
    o.out_dir = (temp_root() / "sim").string();
    o.write_bag = true;
    o.bag2_storages = {"mcap", "sqlite3"};
    sim::run_simulation(o);
    o.out_dir = (temp_root() / "sim_split").string();
    o.write_bag = false;
    o.bag2_storages = {"mcap"};
    o.bag2.compression = "lz4";
    o.bag2.max_file_bytes = 1 << 20;
    sim::run_simulation(o);
    return temp_root() / "sim";
  }();
  return dir;
}

// A bundle whose mission.yaml is `manifest` of `sim_dir`, the rest linked.
fs::path bundle(const std::string& name, const fs::path& sim_dir, const std::string& manifest) {
  const fs::path dir = temp_root() / name;
  fs::create_directories(dir);
  for (const auto& entry : fs::directory_iterator(sim_dir)) {
    const std::string file = entry.path().filename().string();
    if (file.size() > 5 && file.substr(file.size() - 5) == ".yaml") continue;
    fs::create_symlink(entry.path(), dir / file);
  }
  fs::copy_file(sim_dir / manifest, dir / "mission.yaml");
  return dir;
}

struct Variant {
  std::string name;
  fs::path mission;
};

const std::vector<Variant>& variants() {
  static const std::vector<Variant> all = [] {
    const fs::path& sim = simulated();
    std::vector<Variant> v;
    v.push_back({"ros1", bundle("ros1", sim, "mission_bag.yaml")});
    v.push_back({"mcap", bundle("mcap", sim, "mission_mcap.yaml")});
    v.push_back({"db3", bundle("db3", sim, "mission_db3.yaml")});
    v.push_back(
        {"mcap_split_lz4", bundle("split", temp_root() / "sim_split", "mission_mcap.yaml")});
    return v;
  }();
  return all;
}

TEST(Bag2Parity, SplitBagHasSeveralFiles) {
  const fs::path folder = temp_root() / "sim_split" / "mission_mcap";
  (void)variants();
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(folder)) files += e.path().extension() == ".mcap";
  EXPECT_GE(files, 3u);
}

TEST(Bag2Parity, IngestReportsAreTheSame) {
  json reference;
  for (const auto& v : variants()) {
    const json r = testing::run_stage(*make_ingest_stage(), v.mission, json::object(),
                                      temp_root() / ("ingest_" + v.name))
                       .result.report;
    ASSERT_EQ(r["sensors"]["imu"]["count"], 4001) << v.name;  // 200 Hz over 20 s
    if (reference.is_null()) {
      reference = r;
      continue;
    }
    EXPECT_EQ(r["sensors"], reference["sensors"]) << v.name;
    EXPECT_EQ(r["trajectories"], reference["trajectories"]) << v.name;
    EXPECT_EQ(r["warnings"], reference["warnings"]) << v.name;
  }
  EXPECT_GT(reference["sensors"]["lidar_h"]["points"]["total"].get<size_t>(), 100000u);
  EXPECT_EQ(reference["sensors"]["cam0"]["formats"].size(), 1u);
}

TEST(Bag2Parity, RefinedTrajectoriesAndMapsAreTheSame) {
  Trajectory reference;
  json reference_map;
  for (const auto& v : variants()) {
    const fs::path work = temp_root() / ("work_" + v.name);
    testing::run_stage(*make_refine_stage(), v.mission, json::object(), work);
    const Trajectory refined = io::read_tum(work / "trajectory_refined.tum");
    const json map =
        testing::run_stage(*make_map_stage(), v.mission,
                           {{"sensors", {"lidar_h"}}, {"metrics_max_points", 5000}}, work)
            .result.report;
    ASSERT_GT(refined.size(), 10u) << v.name;
    if (reference.empty()) {
      reference = refined;
      reference_map = map;
      continue;
    }
    ASSERT_EQ(refined.size(), reference.size()) << v.name;
    for (size_t i = 0; i < refined.size(); ++i) {
      EXPECT_EQ(refined[i].t_ns, reference[i].t_ns) << v.name;
      EXPECT_LT(
          (refined[i].T_world_body.translation() - reference[i].T_world_body.translation()).norm(),
          1e-9)
          << v.name << " pose " << i;
    }
    EXPECT_EQ(map["sensors"]["lidar_h"]["stats"], reference_map["sensors"]["lidar_h"]["stats"])
        << v.name;
    EXPECT_EQ(fs::file_size(work / "map_lidar_h.drc"),
              fs::file_size(temp_root() / "work_ros1" / "map_lidar_h.drc"))
        << v.name;
  }
}

// A damaged ROS 2 bag fails ingest naming the storage file, the topic and the message.
TEST(Bag2Parity, TruncatedMcapFailsIngestNamingFileTopicAndMessage) {
  const fs::path dir = temp_root() / "truncated";
  fs::create_directories(dir / "mission_mcap");
  for (const auto& entry : fs::directory_iterator(simulated()))
    if (entry.path().filename() != "mission_mcap" && entry.path().extension() != ".yaml")
      fs::create_symlink(entry.path(), dir / entry.path().filename());
  // The lidar only: its channel begins before the cut (the trajectories' come after it).
  std::ofstream(dir / "mission.yaml") << "keel_mission: 1\nname: cut\nplatform: usv\n"
                                         "bag: mission_mcap\nsensors:\n"
                                         "  - {name: lidar_h, type: lidar, topic: "
                                         "/lidar_h/points, rate_hz: 10}\n";
  fs::copy_file(simulated() / "mission_mcap" / "metadata.yaml",
                dir / "mission_mcap" / "metadata.yaml");
  const fs::path mcap = simulated() / "mission_mcap" / "mission_mcap_0.mcap";
  fs::copy_file(mcap, dir / "mission_mcap" / "mission_mcap_0.mcap");
  fs::resize_file(dir / "mission_mcap" / "mission_mcap_0.mcap", fs::file_size(mcap) / 3);
  try {
    testing::run_stage(*make_ingest_stage(), dir, json::object(), temp_root() / "work_cut");
    ADD_FAILURE() << "ingest of a truncated MCAP succeeded";
  } catch (const std::exception& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("mission_mcap/mission_mcap_0.mcap: topic '/lidar_h/points' message "),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("' message "), std::string::npos) << message;
    EXPECT_NE(message.find("truncated MCAP"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace keel::pipeline
