#include "tests/sim/hull_model.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "tests/sim/mesh_bvh.h"
#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"
#include "core/time.h"

namespace keel::sim {
namespace {
namespace fs = std::filesystem;

std::vector<std::vector<std::string>> read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

TEST(Hull, CadMeshIsClosedOutwardAndShipSized) {
  const HullOptions options;
  const TriangleMesh mesh = make_hull_mesh(options);
  EXPECT_GT(mesh.num_faces(), 3000u);
  std::map<std::pair<int, int>, int> directed;
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1) << "edge used twice in the same direction";
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << "open edge";
  }
  // Positive volume (outward faces), below the bounding box and above half of it.
  const double box = options.length_m * options.beam_m * (options.draft_m + options.freeboard_m);
  const double volume = mesh_signed_volume(mesh);
  EXPECT_GT(volume, 0.5 * box);
  EXPECT_LT(volume, box);
}

// The object's base centre is on the real hull and its top stands `height` above it: the CAD
// surface does not have the object, the real hull as the sensors see it does.
void expect_on_real_hull_only(const Scenario& s, const ForeignObject& o) {
  const TriangleMesh real_hull = transform_mesh(s.cad_mesh, s.T_world_cad);
  MeshHit hit;
  ASSERT_TRUE(raycast_brute_force(real_hull, o.center + 0.05 * o.axis, -o.axis, 0.0, 1.0, &hit));
  EXPECT_NEAR(hit.t, 0.05, 0.003);
  const Eigen::Vector3d top = o.center + o.height_m * o.axis;
  ASSERT_TRUE(raycast_brute_force(real_hull, top, -o.axis, 0.0, 1.0, &hit));
  EXPECT_NEAR(hit.t, o.height_m, 0.003);
  ASSERT_TRUE(raycast_brute_force(s.real_mesh_world, top + 0.5 * o.axis, -o.axis, 0.0, 1.0, &hit));
  EXPECT_NEAR(hit.t, 0.5, 0.01) << o.kind_name();
  if (o.kind == ForeignObject::Kind::kCylinder) {
    EXPECT_DOUBLE_EQ(o.height_m, 0.11);
  }
  if (o.kind == ForeignObject::Kind::kPatch) {
    EXPECT_GE(o.height_m, 0.06);
    EXPECT_LE(o.height_m, 0.18);
  }
}

TEST(Hull, ForeignObjectsStandOnTheRealHullNotOnTheCad) {
  const Scenario s = make_scenario("hauv-hull", 21);
  ASSERT_EQ(s.foreign_objects.size(), 4u);
  for (const auto& o : s.foreign_objects) expect_on_real_hull_only(s, o);
  // The misalignment is a few cm and ~1 degree.
  EXPECT_LT(s.T_world_cad.translation().norm(), 0.2);
  const double angle = Eigen::AngleAxisd(s.T_world_cad.linear()).angle() * 180.0 / M_PI;
  EXPECT_GT(angle, 0.6);
  EXPECT_LT(angle, 1.4);
}

size_t landmarks_off_cad(const Scenario& s) {
  size_t n = 0;
  for (const Landmark& l : s.hull_world->landmarks()) n += !l.on_cad;
  return n;
}

TEST(Hull, FoulingPatchesAreAddedOnTheSurveyedHullApartAndLeaveTheRestAlone) {
  const Scenario clean = make_scenario("hauv-hull", 21);
  ScenarioOptions options;
  options.fouling_patches = 20;
  const Scenario fouled = make_scenario("hauv-hull", 21, options);
  ASSERT_EQ(fouled.foreign_objects.size(), 24u);
  // The clean mission's objects, landmarks and misalignment stay as they were.
  EXPECT_TRUE(fouled.T_world_cad.isApprox(clean.T_world_cad, 0.0));
  for (size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(fouled.foreign_objects[k].center, clean.foreign_objects[k].center);
    EXPECT_EQ(fouled.foreign_objects[k].height_m, clean.foreign_objects[k].height_m);
  }
  const size_t clean_on_cad = clean.hull_world->landmarks().size() - landmarks_off_cad(clean);
  EXPECT_EQ(fouled.hull_world->landmarks().size() - landmarks_off_cad(fouled), clean_on_cad);
  EXPECT_GT(landmarks_off_cad(fouled), 4 * landmarks_off_cad(clean));
  // Every patch stands on the real hull, inside the surveyed band (|x| <= 5 m from midship in
  // the CAD frame, below the waterline) and 0.3 m clear of every other object.
  const Pose3 T_cad_world = fouled.T_world_cad.inverse();
  for (size_t k = 4; k < fouled.foreign_objects.size(); ++k) {
    const ForeignObject& o = fouled.foreign_objects[k];
    EXPECT_EQ(o.kind, ForeignObject::Kind::kPatch);
    expect_on_real_hull_only(fouled, o);
    const Eigen::Vector3d c = T_cad_world * o.center;
    EXPECT_LE(std::abs(c.x()), 5.01);
    EXPECT_LT(c.z(), 0.0);
    for (size_t j = 0; j < k; ++j) {
      const ForeignObject& other = fouled.foreign_objects[j];
      EXPECT_GT((other.center - o.center).norm(), other.radius_m + o.radius_m + 0.3) << k << j;
    }
  }
}

TEST(Hull, FoulingPatchesSettingTakesACountAndRefusesTheRest) {
  SensorSettings sensors;
  ScenarioOptions options;
  apply_settings({"hull.fouling_patches=30"}, &sensors, &options);
  EXPECT_EQ(options.fouling_patches, 30);
  apply_settings({"hull.fouling_patches=0"}, &sensors, &options);
  EXPECT_EQ(options.fouling_patches, 0);
  for (const char* text :
       {"hull.fouling_patches=-1", "hull.fouling_patches=2.5", "hull.fouling_patches=61"}) {
    try {
      apply_settings({text}, &sensors, &options);
      ADD_FAILURE() << text << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("hull.fouling_patches"), std::string::npos) << e.what();
    }
  }
  for (int count : {-1, kMaxFoulingPatches + 1}) {  // options set directly are checked too
    options.fouling_patches = count;
    try {
      make_scenario("hauv-hull", 1, options);
      ADD_FAILURE() << count << " patches accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("hull.fouling_patches"), std::string::npos) << e.what();
    }
  }
  options.fouling_patches = kMaxFoulingPatches;  // the largest count fits
  EXPECT_EQ(make_scenario("hauv-hull", 10, options).foreign_objects.size(),
            size_t(4 + kMaxFoulingPatches));
  options.fouling_patches = 3;  // only the hull has a hull to foul
  for (const char* name : {"usv-bridge", "usv-corridor"}) {
    try {
      make_scenario(name, 1, options);
      ADD_FAILURE() << name << " accepted fouling patches";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("hull.fouling_patches"), std::string::npos) << e.what();
    }
  }
}

class HullMission : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("keel_sim_hull_" + std::to_string(::getpid()));
    SimOptions options;
    options.scenario = "hauv-hull";
    options.seed = 4;
    options.out_dir = dir_.string();
    options.duration_s = 8.0;
    options.sensors = {"dvl", "camera"};
    options.t0_ns = 0;
    run_simulation(options);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
};
fs::path HullMission::dir_;

// DVL beam ranges equal casts against the real hull (brute force) within 5 sigma (3 mm).
TEST_F(HullMission, DvlRangesMatchRaycastsAgainstTheRealHull) {
  const Scenario s = make_scenario("hauv-hull", 4);
  const auto beams = janus_beams(30.0);
  const auto rows = read_csv(dir_ / "dvl_ranges.csv");
  ASSERT_GT(rows.size(), 100u);
  int checked = 0, close = 0;
  for (size_t i = 0; i < rows.size(); i += 7) {
    const double t = parse_seconds_exact(rows[i][0]) * 1e-9;
    const KinematicState st = s.motion->state(t);
    Pose3 T_world_body = Pose3::Identity();
    T_world_body.linear() = st.q_world_body.toRotationMatrix();
    T_world_body.translation() = st.p_world;
    const Pose3 T_world_dvl = T_world_body * s.T_body_sensor_at("dvl_ranges", t);
    for (int b = 0; b < 4; ++b) {
      MeshHit hit;
      const bool found = raycast_brute_force(s.real_mesh_world, T_world_dvl.translation(),
                                             T_world_dvl.linear() * beams[b], 0.05, 50.0, &hit);
      const double measured = std::stod(rows[i][1 + b]);
      ASSERT_EQ(found, !std::isnan(measured));
      if (!found) continue;
      ++checked;
      close += std::abs(measured - hit.t) < 5 * 0.003;
      // 1.5 m standoff along 30-degree beams (plus misalignment and hull curvature).
      EXPECT_NEAR(hit.t * std::cos(M_PI / 6), 1.5, 0.35);
    }
  }
  ASSERT_GT(checked, 40);
  EXPECT_GE(close, checked - 1);
}

// landmarks.csv lists every painted blob of the scene: its centre, whether it is on the CAD
// hull, and the radius its paint reaches (what bench_texture needs to know what is textured).
TEST_F(HullMission, LandmarksFileListsEveryBlobWithItsRadius) {
  const Scenario s = make_scenario("hauv-hull", 4);
  std::ifstream in(dir_ / "ground_truth" / "landmarks.csv");
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "id,x,y,z,on_cad,radius_m");
  const auto rows = read_csv(dir_ / "ground_truth" / "landmarks.csv");
  const auto& landmarks = s.hull_world->landmarks();
  ASSERT_EQ(rows.size(), landmarks.size());
  for (size_t k = 0; k < rows.size(); ++k) {
    ASSERT_EQ(rows[k].size(), 6u);
    EXPECT_EQ(std::stoll(rows[k][0]), landmarks[k].id);
    EXPECT_NEAR(std::stod(rows[k][1]), landmarks[k].p_world.x(), 1e-6);
    EXPECT_EQ(rows[k][4] == "1", landmarks[k].on_cad);
    EXPECT_NEAR(std::stod(rows[k][5]), landmarks[k].radius_m, 1e-6);
    EXPECT_GE(landmarks[k].radius_m, 0.015);
    EXPECT_LE(landmarks[k].radius_m, 0.04);
  }
}

TEST_F(HullMission, ImagesAreTexturedPngsAndTracksHitTheBlobs) {
  const auto index = read_csv(dir_ / "cam0" / "index.csv");
  ASSERT_EQ(index.size(), 17u);  // 2 Hz over 8 s
  const cv::Mat image = cv::imread((dir_ / "cam0" / index[8][1]).string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.type(), CV_8UC1);
  EXPECT_EQ(image.cols, 640);
  EXPECT_EQ(image.rows, 480);
  cv::Scalar mean, stddev;
  cv::meanStdDev(image, mean, stddev);
  EXPECT_GT(stddev[0], 15.0);
  std::vector<cv::KeyPoint> keypoints;
  cv::SIFT::create()->detect(image, keypoints);
  EXPECT_GT(keypoints.size(), 50u);

  // Ground-truth tracks: the pixel under a dark landmark is darker than under a bright one.
  const Scenario s = make_scenario("hauv-hull", 4);
  std::map<int64_t, double> albedo;
  for (const auto& l : s.hull_world->landmarks()) albedo[l.id] = l.albedo;
  const auto tracks = read_csv(dir_ / "ground_truth" / "cam0_tracks.csv");
  ASSERT_GT(tracks.size(), 200u);
  double dark = 0, bright = 0;
  int n_dark = 0, n_bright = 0;
  for (const auto& row : tracks) {
    if (row[1] != index[8][0]) continue;
    const int u = static_cast<int>(std::lround(std::stod(row[2])));
    const int v = static_cast<int>(std::lround(std::stod(row[3])));
    const double value = image.at<uint8_t>(v, u);
    if (albedo.at(std::stoll(row[0])) < 0.5)
      dark += value, ++n_dark;
    else
      bright += value, ++n_bright;
  }
  ASSERT_GT(n_dark, 10);
  ASSERT_GT(n_bright, 10);
  EXPECT_LT(dark / n_dark + 40.0, bright / n_bright);
}

}  // namespace
}  // namespace keel::sim
