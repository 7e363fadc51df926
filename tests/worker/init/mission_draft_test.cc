// keel init: the draft of keel-sim's bags (ROS1, MCAP, db3) reproduces the hand-written
// mission's sensors, rates (exactly: the simulated rates are whole hertz and the draft rounds
// a measured rate within 2% to whole hertz), extrinsics (within 1e-9 m and 1e-9 rad, the
// draft prints 10 significant digits) and point-time fields, and passes ingest unedited; the
// time-field recogniser reads each driver convention; on real recordings (nebula's Velodyne
// test bags, rosbag2's test bags) the table's counts and types equal the bag's metadata.yaml.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "tests/sim/simulator.h"
#include "tests/worker/pipeline/stage_run.h"
#include "worker/init/bag_survey.h"
#include "worker/init/init_command.h"
#include "worker/init/mission_draft.h"
#include "worker/init/point_time_guess.h"
#include "worker/io/bag/bag_source.h"
#include "worker/io/mission.h"
#include "worker/pipeline/stage.h"

namespace keel::init {
namespace {

namespace fs = std::filesystem;
using proto::TimeReference;
using proto::TimeUnit;

fs::path temp_root() { return fs::temp_directory_path() / "keel-init-test"; }

const fs::path& simulated() {
  static const fs::path dir = [] {
    fs::remove_all(temp_root());
    sim::SimOptions o;
    o.scenario = "usv-bridge";
    o.seed = 5;
    o.duration_s = 6.0;
    o.sensors = {"imu", "dvl", "lidar_h", "lidar_v", "sonar", "camera"};
    o.out_dir = (temp_root() / "sim").string();
    o.write_bag = true;
    o.bag2_storages = {"mcap", "sqlite3"};
    sim::run_simulation(o);
    return temp_root() / "sim";
  }();
  return dir;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Pose3 pose_of(const proto::Extrinsic& e) {
  const auto& t = e.translation;
  const auto& q = e.rotation_xyzw;
  return make_pose(Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized(),
                   Eigen::Vector3d(t[0], t[1], t[2]));
}

struct SimBag {
  const char* bag;       // in the simulation folder
  const char* manifest;  // the hand-written manifest of that bag
};

class SimBags : public ::testing::TestWithParam<SimBag> {};

TEST_P(SimBags, DraftReproducesTheHandWrittenMissionAndPassesIngest) {
  const SimBag& p = GetParam();
  const fs::path& sim = simulated();
  // A bundle holding only the bag: the draft is its mission.yaml, unedited.
  const fs::path bundle = temp_root() / (std::string("bundle_") + p.bag);
  fs::remove_all(bundle);
  fs::create_directories(bundle);
  fs::create_symlink(sim / p.bag, bundle / p.bag);
  InitArgs args;
  args.bag = bundle / p.bag;
  args.output = bundle / "mission.yaml";
  std::ostringstream out, err;
  ASSERT_EQ(run_init(args, out, err), 0) << err.str();
  EXPECT_NE(out.str().find("/lidar_h/points"), std::string::npos) << out.str();

  const io::Mission draft = io::load_mission(bundle);
  const fs::path hand_dir = temp_root() / (std::string("hand_") + p.bag);
  fs::remove_all(hand_dir);
  fs::create_directories(hand_dir);
  for (const auto& entry : fs::directory_iterator(sim)) {  // the CSV and TUM files it names
    const std::string file = entry.path().filename().string();
    if (file.size() > 5 && file.substr(file.size() - 5) == ".yaml") continue;
    fs::create_symlink(entry.path(), hand_dir / file);
  }
  fs::copy_file(sim / p.manifest, hand_dir / "mission.yaml");
  const io::Mission hand = io::load_mission(hand_dir);

  const auto& d = draft.manifest;
  const auto& h = hand.manifest;
  EXPECT_EQ(d.body_frame, h.body_frame);
  size_t compared = 0;
  for (const auto& hs : h.sensors) {
    if (hs.topic.empty()) continue;  // a CSV sensor (depth.csv): not in the bag
    if (hs.type == proto::SensorType::kCamera) {
      // Intrinsics are not in the bag: the draft comments the camera out and asks for them.
      EXPECT_NE(read_text(bundle / "mission.yaml").find("# - name: cam0"), std::string::npos);
      continue;
    }
    const proto::SensorSpec* ds = nullptr;
    for (const auto& s : d.sensors)
      if (s.topic == hs.topic) ds = &s;
    ASSERT_NE(ds, nullptr) << hs.topic;
    ++compared;
    EXPECT_EQ(ds->name, hs.name);
    EXPECT_EQ(ds->type, hs.type) << hs.name;
    EXPECT_EQ(ds->rate_hz, hs.rate_hz) << hs.name;
    ASSERT_TRUE(ds->T_body_sensor && hs.T_body_sensor) << hs.name;
    const Pose3 a = pose_of(*ds->T_body_sensor), b = pose_of(*hs.T_body_sensor);
    EXPECT_LT((a.translation() - b.translation()).norm(), 1e-9) << hs.name;
    EXPECT_LT(Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle(), 1e-9) << hs.name;
    EXPECT_EQ(ds->point_time.has_value(), hs.point_time.has_value()) << hs.name;
    if (ds->point_time && hs.point_time) {
      EXPECT_EQ(ds->point_time->field, hs.point_time->field);
      EXPECT_EQ(ds->point_time->unit, hs.point_time->unit);
      EXPECT_EQ(ds->point_time->reference, hs.point_time->reference);
    }
  }
  EXPECT_EQ(compared, 5u);  // imu, dvl, lidar_h, lidar_v, sonar
  ASSERT_EQ(d.trajectories.count("map"), 1u);
  ASSERT_EQ(d.trajectories.count("odometry"), 1u);
  EXPECT_EQ(d.trajectories.at("map").topic, h.trajectories.at("map").topic);
  EXPECT_EQ(d.trajectories.at("odometry").topic, h.trajectories.at("odometry").topic);

  const nlohmann::json report =
      pipeline::testing::run_stage(*pipeline::make_ingest_stage(), bundle, nlohmann::json::object(),
                                   temp_root() / ("ingest_" + std::string(p.bag)))
          .result.report;
  EXPECT_EQ(report["sensors"]["imu"]["count"], 1201) << report.dump(1);  // 200 Hz over 6 s
  EXPECT_EQ(report["sensors"]["lidar_h"]["time_field"]["stamp_marks"], "first point");
}

INSTANTIATE_TEST_SUITE_P(, SimBags,
                         ::testing::Values(SimBag{"mission.bag", "mission_bag.yaml"},
                                           SimBag{"mission_mcap", "mission_mcap.yaml"},
                                           SimBag{"mission_db3", "mission_db3.yaml"}),
                         [](const auto& info) {
                           std::string n = info.param.bag;
                           for (char& c : n)
                             if (c == '.') c = '_';
                           return n;
                         });

TEST(MissionDraft, MissingTrajectoryIsSaidInTheUsersTerms) {
  BagSurvey survey;
  survey.bag = "imu_only.bag";
  TopicSurvey imu;
  imu.topic = "/imu/data";
  imu.type = imu.plain_type = "sensor_msgs/Imu";
  imu.messages = 101;
  imu.rate_hz = 100.0;
  survey.topics.push_back(imu);
  const MissionDraft d = draft_mission(survey, {});
  bool found = false;
  for (const auto& m : d.missing)
    found = found || m.find("the refine and map stages need `map` and `odometry` poses") !=
                         std::string::npos;
  EXPECT_TRUE(found);
  EXPECT_NE(d.yaml.find("# MISSING: no `map` trajectory topic"), std::string::npos) << d.yaml;
}

// A 0.1 s sweep of 200 points in the convention, stamped at its first or last point.
io::PackedCloud sweep_in(const proto::PointTimeSpec& spec, io::FieldType type, TimeNs stamp_ns,
                         bool stamp_at_end) {
  PointCloud c;
  c.t_ns = stamp_ns;
  for (int i = 0; i < 200; ++i) {
    c.xyz.emplace_back(1.0f * i, 0.0f, 0.0f);
    const double t = 0.1 * i / 199.0;
    c.time_s.push_back(static_cast<float>(stamp_at_end ? t - 0.1 : t));
  }
  return io::pack_cloud(c, io::PointTimeEncoding{spec, type});
}

TEST(PointTimeGuess, RecognisesEachDriverConvention) {
  const TimeNs stamp = 1700000000500000000LL;
  struct Case {
    const char* name;
    proto::PointTimeSpec written;
    io::FieldType type;
    bool at_end;
  };
  proto::PointTimeSpec split_abs{"time_sec", TimeUnit::kSeconds, TimeReference::kAbsolute};
  split_abs.nsec_field = "time_nsec";
  proto::PointTimeSpec split_end{"sec", TimeUnit::kSeconds, TimeReference::kScanEnd};
  split_end.nsec_field = "nsec";
  const Case cases[] = {
      {"velodyne",
       {"time", TimeUnit::kSeconds, TimeReference::kScanStart},
       io::FieldType::kFloat32,
       false},
      {"velodyne stamped at the last packet",
       {"time", TimeUnit::kSeconds, TimeReference::kScanEnd},
       io::FieldType::kFloat32,
       true},
      {"ouster",
       {"t", TimeUnit::kNanoseconds, TimeReference::kScanStart},
       io::FieldType::kUint32,
       false},
      {"livox/hesai",
       {"timestamp", TimeUnit::kSeconds, TimeReference::kAbsolute},
       io::FieldType::kFloat64,
       false},
      {"absolute ns",
       {"timestamp", TimeUnit::kNanoseconds, TimeReference::kAbsolute},
       io::FieldType::kUint64,
       false},
      {"split absolute", split_abs, io::FieldType::kUint32, true},
      {"split relative at the end", split_end, io::FieldType::kInt32, true},
  };
  for (const Case& c : cases) {
    const io::PackedCloud packed = sweep_in(c.written, c.type, stamp, c.at_end);
    const PointTimeGuess g = guess_point_time(packed.view(), stamp, 0.1);
    ASSERT_TRUE(g.spec) << c.name << ": " << g.evidence;
    EXPECT_TRUE(g.certain) << c.name << ": " << g.evidence;
    EXPECT_EQ(g.spec->field, c.written.field) << c.name;
    EXPECT_EQ(g.spec->nsec_field, c.written.nsec_field) << c.name;
    EXPECT_EQ(g.spec->reference, c.written.reference) << c.name << ": " << g.evidence;
    if (!c.written.is_split()) EXPECT_EQ(g.spec->unit, c.written.unit) << c.name;
    const bool says_end = g.evidence.find("marks the last point") != std::string::npos;
    EXPECT_EQ(says_end, c.at_end) << c.name << ": " << g.evidence;
  }
}

// The bag's metadata.yaml read independently (yaml-cpp): topic -> (type, count).
std::map<std::string, std::pair<std::string, size_t>> metadata_topics(const fs::path& folder) {
  const YAML::Node root = YAML::LoadFile((folder / "metadata.yaml").string());
  std::map<std::string, std::pair<std::string, size_t>> out;
  for (const auto& t : root["rosbag2_bagfile_information"]["topics_with_message_count"])
    out[t["topic_metadata"]["name"].as<std::string>()] = {
        t["topic_metadata"]["type"].as<std::string>(), t["message_count"].as<size_t>()};
  return out;
}

void expect_table_equals_metadata(const fs::path& folder) {
  const auto bag = io::open_bag(folder);
  const BagSurvey s = survey_bag(*bag);
  const auto expected = metadata_topics(folder);
  ASSERT_EQ(s.topics.size(), expected.size()) << folder;
  for (const auto& t : s.topics) {
    ASSERT_EQ(expected.count(t.topic), 1u) << folder << " " << t.topic;
    EXPECT_EQ(t.type, expected.at(t.topic).first) << folder << " " << t.topic;
    EXPECT_EQ(t.messages, expected.at(t.topic).second) << folder << " " << t.topic;
  }
}

TEST(RealBags, NebulaVelodyneTablesAndModels) {
  const char* root = std::getenv("KEEL_NEBULA_TESTDATA");
  if (!root) GTEST_SKIP() << "set KEEL_NEBULA_TESTDATA to nebula's src/nebula_velodyne folder";
  const fs::path truth = fs::path(root) / "nebula_velodyne/test_resources/decoder_ground_truth";
  if (!fs::is_directory(truth)) GTEST_SKIP() << "KEEL_NEBULA_TESTDATA: no " << truth;
  const std::map<std::string, std::string> model = {
      {"vlp16", "VLP16"}, {"vlp32", "VLP32C"}, {"vls128", ""}};
  size_t bags = 0;
  for (const auto& [sensor, expected_model] : model) {
    for (const auto& e : fs::directory_iterator(truth / sensor)) {
      if (!fs::is_directory(e.path())) continue;
      ++bags;
      expect_table_equals_metadata(e.path());
      const auto bag = io::open_bag(e.path());
      const BagSurvey s = survey_bag(*bag);
      ASSERT_TRUE(s.topics.at(0).velodyne) << e.path();
      EXPECT_EQ(velodyne_model(s.topics[0].velodyne->product), expected_model) << e.path();
      const MissionDraft d = draft_mission(s, {});
      if (expected_model.empty())
        EXPECT_NE(d.yaml.find("CONFIRM the model"), std::string::npos) << d.yaml;
      else
        EXPECT_NE(d.yaml.find("packets: {model: " + expected_model + "}"), std::string::npos)
            << d.yaml;
    }
  }
  EXPECT_EQ(bags, 3u);
}

TEST(RealBags, Rosbag2TestDataTablesEqualMetadata) {
  const char* root = std::getenv("KEEL_ROSBAG2_TESTDATA");
  if (!root) root = KEEL_ROSBAG2_TESTDATA;
  if (!*root) GTEST_SKIP() << "set KEEL_ROSBAG2_TESTDATA to rosbag2's test bags";
  size_t bags = 0;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.path().filename() != "metadata.yaml") continue;
    const fs::path folder = e.path().parent_path();
    try {
      io::open_bag(folder);
    } catch (const std::exception& err) {
      continue;  // a storage or compression Keel does not read: rosbag2_reader_test's matter
    }
    ++bags;
    expect_table_equals_metadata(folder);
  }
  EXPECT_GT(bags, 0u);
}

}  // namespace
}  // namespace keel::init
