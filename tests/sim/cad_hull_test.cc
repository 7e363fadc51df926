#include "tests/sim/cad_hull.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "tests/sim/bundle_files.h"
#include "tests/sim/inertial_sensors.h"
#include "tests/sim/mesh_bvh.h"
#include "tests/sim/scenarios.h"
#include "tests/sim/simulator.h"

namespace keel::sim {
namespace {
namespace fs = std::filesystem;

fs::path kcs_stl() { return fs::path(KEEL_SHARED_DIR) / "data" / "KCS.stl"; }

// The procedural hull written as a file, in millimetres: load_cad_hull must give back the
// same hull (x along it, z up, waterline at z = 0 for the procedural draft). Drawn deeper
// than keel-sim's own hull, a ship's side above the bilge for the survey band.
class ProceduralHullFile : public ::testing::Test {
 protected:
  void SetUp() override {
    hull_.draft_m = 9.0;
    path_ = fs::temp_directory_path() / ("keel_cad_hull_" + std::to_string(::getpid()) + ".ply");
    TriangleMesh mm = make_hull_mesh(hull_);
    for (Eigen::Vector3d& v : mm.vertices) v *= 1000.0;
    write_ply_binary(path_.string(), mm);
  }
  void TearDown() override { fs::remove(path_); }
  HullOptions hull_;
  fs::path path_;
};

TEST_F(ProceduralHullFile, MillimetresAreRefusedNamingTheScaleAndScaledBack) {
  CadHullOptions options;
  options.path = path_.string();
  try {
    load_cad_hull(options);
    ADD_FAILURE() << "a 20 km hull accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("hull.cad_scale=0.001"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path_.filename().string()), std::string::npos);
  }
  options.scale = 0.001;
  options.draft_m = hull_.draft_m;
  const TriangleMesh mesh = load_cad_hull(options);
  const TriangleMesh truth = make_hull_mesh(hull_);
  // The procedural keel is at z = -draft: a draft of hull_.draft_m keeps every vertex.
  ASSERT_EQ(mesh.vertices.size(), truth.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); i += 97)
    EXPECT_LT((mesh.vertices[i] - truth.vertices[i]).norm(), 1e-3);
}

// On the procedural hull, the traced section is the analytic one: every surface point lies
// on the mesh (a ray along its normal hits it at once), below the waterline on starboard
// (y < 0), with the lanes' girths 1.07 m apart as on the procedural hull.
TEST_F(ProceduralHullFile, SurfacePointsLieOnTheWettedStarboardSide) {
  CadHullOptions options;
  options.path = path_.string();
  options.scale = 0.001;
  options.draft_m = hull_.draft_m;
  const TriangleMesh mesh = load_cad_hull(options);
  const CadHullSurface surface(mesh, 0.5);
  const MeshBvh bvh(mesh);
  for (double x : {-5.0, -2.0, 0.0, 3.0, 5.0}) {
    for (double sigma : {0.33, 0.46, 0.59, 0.72, 0.85}) {
      const SurfacePoint sp = surface.surface(x, sigma);
      EXPECT_LT(sp.p.y(), 0.0);
      EXPECT_LT(sp.p.z(), 0.0);
      EXPECT_NEAR(sp.normal.norm(), 1.0, 1e-9);
      MeshHit hit;
      ASSERT_TRUE(bvh.raycast(sp.p + 0.2 * sp.normal, -sp.normal, 0.0, 1.0, &hit));
      EXPECT_NEAR(hit.t, 0.2, 0.01) << x << " " << sigma;
      EXPECT_GT(bvh.normal(hit.triangle).dot(sp.normal), 0.97);  // outward, like the mesh
    }
  }
  // Girth between lanes: sigma steps of 0.13 are 0.13 * 8.24 m of arc.
  const Eigen::Vector3d a = surface.surface(0.0, 0.59).p, b = surface.surface(0.0, 0.60).p;
  EXPECT_NEAR((a - b).norm(), 0.01 * CadHullSurface::kGirthPerSigmaM, 0.01);
}

TEST(CadHull, MissingAndUnreadableFilesAreNamed) {
  CadHullOptions options;
  options.path = "/nonexistent/hull.stl";
  try {
    load_cad_hull(options);
    ADD_FAILURE() << "a missing file accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("hull.stl"), std::string::npos) << e.what();
  }
  SensorSettings sensors;
  ScenarioOptions scenario;
  EXPECT_THROW(apply_settings({"hull.cad="}, &sensors, &scenario), std::invalid_argument);
  EXPECT_THROW(apply_settings({"hull.cad_scale=0"}, &sensors, &scenario), std::invalid_argument);
  EXPECT_THROW(apply_settings({"hull.cad_survey_x=1.5"}, &sensors, &scenario),
               std::invalid_argument);
  apply_settings({"hull.cad=x.stl", "hull.cad_scale=0.001", "hull.cad_z_down=1"}, &sensors,
                 &scenario);
  EXPECT_EQ(scenario.cad.path, "x.stl");
  EXPECT_EQ(scenario.cad.scale, 0.001);
  EXPECT_TRUE(scenario.cad.z_down);
  scenario.cad.path = "x.stl";
  EXPECT_THROW(make_scenario("usv-bridge", 1, scenario), std::invalid_argument);
}

Pose3 body_pose(const Scenario& s, double t) {
  const KinematicState st = s.motion->state(t);
  Pose3 T_world_body = Pose3::Identity();
  T_world_body.linear() = st.q_world_body.toRotationMatrix();
  T_world_body.translation() = st.p_world;
  return T_world_body;
}

// The KRISO container ship (230 m, full scale): the whole mission, checked against the mesh.
class KcsSurvey : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!fs::exists(kcs_stl())) return;
    ScenarioOptions options;
    options.cad.path = kcs_stl().string();
    scenario_ = new Scenario(make_scenario("hauv-hull", 1, options));
  }
  static void TearDownTestSuite() {
    delete scenario_;
    scenario_ = nullptr;
  }
  void SetUp() override {
    if (!scenario_) GTEST_SKIP() << kcs_stl() << " absent (shared/data/KCS.stl)";
  }
  static Scenario* scenario_;
};
Scenario* KcsSurvey::scenario_ = nullptr;

TEST_F(KcsSurvey, LanesRunAlongTheWettedStarboardSideAtTheStandoff) {
  const Scenario& s = *scenario_;
  EXPECT_GT(s.cad_mesh.num_faces(), 10000u);
  const Pose3 T_cad_world = s.T_world_cad.inverse();
  Eigen::AlignedBox3d box;
  for (const auto& v : s.cad_mesh.vertices) box.extend(v);
  // KCS: 230 m between perpendiculars, 32.2 m beam.
  EXPECT_GT(box.sizes().x(), 230.0);
  EXPECT_LT(box.sizes().x(), 250.0);
  EXPECT_NEAR(box.sizes().y(), 32.2, 0.1);
  const MeshBvh real(s.real_mesh_world);
  const auto beams = janus_beams(30.0);
  int samples = 0;
  double x_min = 1e9, x_max = -1e9;
  for (double t = 0.0; t <= s.motion->end_time(); t += 0.5, ++samples) {
    const Pose3 T_world_dvl = body_pose(s, t) * s.T_body_sensor_at("dvl_ranges", t);
    const Eigen::Vector3d p_cad = T_cad_world * T_world_dvl.translation();
    EXPECT_LT(p_cad.y(), 0.0) << "t " << t;  // starboard
    EXPECT_LT(p_cad.z(), 0.0) << "t " << t;  // below the waterline
    x_min = std::min(x_min, p_cad.x()), x_max = std::max(x_max, p_cad.x());
    // Every beam hits the hull; along a 30-degree beam the range is the standoff / cos 30.
    for (const Eigen::Vector3d& beam : beams) {
      MeshHit hit;
      if (!real.raycast(T_world_dvl.translation(), T_world_dvl.linear() * beam, 0.05, 50.0, &hit)) {
        ADD_FAILURE() << "t " << t << " " << p_cad.transpose() << " dir "
                      << (T_cad_world.linear() * T_world_dvl.linear() * beam).transpose();
        continue;
      }
      EXPECT_NEAR(hit.t * std::cos(M_PI / 6), 1.5, 0.35) << "t " << t;
    }
  }
  EXPECT_GT(samples, 300);
  // Lanes 10 m long along the hull, round the survey's centre (the middle of the ship).
  EXPECT_GT(x_max - x_min, 9.5);
  EXPECT_NEAR(0.5 * (x_min + x_max), 0.5 * (box.min().x() + box.max().x()), 1.0);
}

TEST_F(KcsSurvey, EveryCameraRayHitsTheHull) {
  const Scenario& s = *scenario_;
  const MeshBvh real(s.real_mesh_world);
  const CameraModel& camera = s.camera;
  int rays = 0;
  for (double t = 0.0; t <= s.motion->end_time(); t += 1.0 / s.camera_rate_hz) {
    const Pose3 T_world_cam = body_pose(s, t) * s.T_body_sensor_at("cam0", t);
    for (int v = 0; v < camera.height; v += 40) {
      for (int u = 0; u < camera.width; u += 40) {
        Eigen::Vector3d ray;
        ASSERT_TRUE(camera.unproject(u, v, &ray));
        MeshHit hit;
        ASSERT_TRUE(real.raycast(T_world_cam.translation(), T_world_cam.linear() * ray, 0.0,
                                 CameraRenderOptions{}.max_range_m, &hit))
            << "t " << t << " pixel " << u << "," << v;
        EXPECT_LT(hit.t, 5.0);  // the hull, not a far part of the ship
        ++rays;
      }
    }
  }
  EXPECT_GT(rays, 400 * 192);
}

TEST_F(KcsSurvey, ObjectsStandOnTheSurveyedHull) {
  const Scenario& s = *scenario_;
  ASSERT_EQ(s.foreign_objects.size(), 4u);
  const MeshBvh cad(s.cad_mesh);
  const Pose3 T_cad_world = s.T_world_cad.inverse();
  for (const ForeignObject& o : s.foreign_objects) {
    // The base on the real (misaligned) hull, the top `height` above it.
    const Eigen::Vector3d base = T_cad_world * o.center;
    const Eigen::Vector3d axis = T_cad_world.linear() * o.axis;
    MeshHit hit;
    ASSERT_TRUE(cad.raycast(base + 0.05 * axis, -axis, 0.0, 1.0, &hit));
    EXPECT_NEAR(hit.t, 0.05, 0.003);
    EXPECT_LT(base.y(), 0.0);
    EXPECT_LT(base.z(), 0.0);
  }
  // The misalignment turns about the surveyed part: a few cm there, not metres.
  const Eigen::Vector3d center = s.foreign_objects[0].center;
  EXPECT_LT((s.T_world_cad.inverse() * center - center).norm(), 0.3);
}

// A short stretch of the real mission: the DVL sees the hull on every beam.
TEST_F(KcsSurvey, SimulatedDvlRangesAreAllValid) {
  const fs::path dir = fs::temp_directory_path() / ("keel_sim_kcs_" + std::to_string(::getpid()));
  SimOptions options;
  options.scenario = "hauv-hull";
  options.seed = 1;
  options.out_dir = dir.string();
  options.duration_s = 6.0;
  options.sensors = {"dvl"};
  options.t0_ns = 0;
  options.settings = {"hull.cad=" + kcs_stl().string()};
  run_simulation(options);
  std::ifstream in(dir / "dvl_ranges.csv");
  std::string line;
  std::getline(in, line);
  int rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    EXPECT_EQ(line.find("nan"), std::string::npos) << line;
  }
  EXPECT_GT(rows, 50);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace keel::sim
