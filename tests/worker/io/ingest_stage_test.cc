#include "worker/stages/ingest/stage.h"

#include <gtest/gtest.h>

#include "io_test_util.h"
#include "test_bundle.h"

namespace keel::pipeline {
namespace {

using io::testing::TempDir;

TEST(IngestStage, ReportsCountsRatesGapsPointsAndPaths) {
  TempDir dir;
  const auto figures = io::testing::write_bundle(dir.path(), /*imu_gap=*/true);
  StageContext context;
  context.mission_dir = dir.path();
  context.work_dir = dir.path();
  std::vector<double> progress;
  context.progress = [&](double p) { progress.push_back(p); };
  auto stage = make_ingest_stage();
  EXPECT_EQ(stage->name(), "ingest");
  const StageResult result = stage->run(context);
  const auto& r = result.report;
  EXPECT_TRUE(result.artifacts.empty());
  EXPECT_EQ(r["mission"]["name"], "test-bundle");

  const auto& imu = r["sensors"]["imu"];
  EXPECT_EQ(imu["type"], "imu");
  EXPECT_EQ(imu["count"], figures.imu_samples - figures.imu_dropped);
  EXPECT_DOUBLE_EQ(imu["duration_s"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(imu["rate_hz_measured"].get<double>(), 350.0 / 2.0);
  EXPECT_EQ(imu["gaps"]["count"], 1);
  EXPECT_NEAR(imu["gaps"]["longest_interval_s"].get<double>(), 51 * 0.005, 1e-12);
  EXPECT_EQ(imu["extrinsic"], "mission.yaml");

  const auto& dvl = r["sensors"]["dvl"];
  EXPECT_EQ(dvl["count"], figures.dvl_samples);
  EXPECT_NEAR(dvl["rate_hz_measured"].get<double>(), 20.0, 1e-9);
  EXPECT_EQ(dvl["gaps"]["count"], 0);

  const auto& lidar = r["sensors"]["lidar_h"];
  EXPECT_EQ(lidar["count"], figures.scans);
  EXPECT_EQ(lidar["points"]["total"], 100 + 110 + 120 + 130 + 140);
  EXPECT_EQ(lidar["points"]["per_scan"]["min"], 100.0);
  EXPECT_EQ(lidar["points"]["per_scan"]["mean"], 120.0);
  EXPECT_EQ(lidar["points"]["per_scan"]["max"], 140.0);
  EXPECT_NEAR(lidar["time_field"]["span_s"]["max"].get<double>(), 0.1, 1e-6);
  EXPECT_NEAR(lidar["time_field"]["offset_min_s"].get<double>(), 0.0, 1e-9);

  const auto& cam = r["sensors"]["cam0"];
  EXPECT_EQ(cam["count"], figures.images);
  EXPECT_EQ(cam["formats"][0], nlohmann::json({8, 6, 1, 8}));

  const auto& odometry = r["trajectories"]["odometry"];
  EXPECT_EQ(odometry["count"], figures.odometry_poses);
  EXPECT_NEAR(odometry["path_length_m"].get<double>(), 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(odometry["duration_s"].get<double>(), 2.0);
  EXPECT_EQ(r["trajectories"]["map"]["count"], 3);

  bool gap_warned = false;
  for (const auto& w : r["warnings"])
    gap_warned = gap_warned || w.get<std::string>().find("imu: 1 gaps") == 0;
  EXPECT_TRUE(gap_warned) << r["warnings"].dump();
  ASSERT_FALSE(progress.empty());
  EXPECT_EQ(progress.back(), 1.0);
  for (size_t i = 1; i < progress.size(); ++i) EXPECT_GE(progress[i], progress[i - 1]);
}

TEST(IngestStage, BadBundleFailsNamingTheFileAndCancelStops) {
  TempDir dir;
  io::testing::write_bundle(dir.path());
  io::testing::write_text(dir / "dvl.csv", "t,vx,vy,vz\n1.0,0,0,0\n0.5,0,0,0\n");
  StageContext context;
  context.mission_dir = dir.path();
  io::testing::expect_error([&] { make_ingest_stage()->run(context); },
                            {"dvl.csv:3:", "decreasing"});

  io::testing::write_bundle(dir.path());
  context.canceled = [] { return true; };
  EXPECT_THROW(make_ingest_stage()->run(context), Canceled);
  context.canceled = [] { return false; };
  context.options = {{"gap_factr", 3}};
  io::testing::expect_error(
      [&] { make_ingest_stage()->run(context); },
      {"options.ingest.gap_factr: unknown option (known: gap_factor, rate_tolerance)"});
}

TEST(IngestStage, ImageSizeDifferentFromTheCameraModelIsAnError) {
  TempDir dir;
  io::testing::write_bundle(dir.path());
  io::ImageFrame image{0, 9, 6, 1, 8, std::vector<uint8_t>(54, 0)};
  io::write_png(dir / "cam0" / "img_1.png", image);
  StageContext context;
  context.mission_dir = dir.path();
  io::testing::expect_error([&] { make_ingest_stage()->run(context); },
                            {"img_1.png", "9x6", "8x6"});
}

// A cube of side `side_m` with one corner at the origin as OBJ text: 8 vertices, 12 outward
// triangles (two per face); `skip_face` in [0, 6) leaves out that face's two triangles.
std::string cube_obj(double side_m, int skip_face = -1) {
  std::string text;
  for (int i = 0; i < 8; ++i)
    text += "v " + std::to_string(side_m * (i & 1)) + " " + std::to_string(side_m * (i >> 1 & 1)) +
            " " + std::to_string(side_m * (i >> 2 & 1)) + "\n";
  // Quads (1-based, counter-clockwise from outside): -z, +z, -y, +y, -x, +x.
  const int quads[6][4] = {{1, 3, 4, 2}, {5, 6, 8, 7}, {1, 2, 6, 5},
                           {3, 7, 8, 4}, {1, 5, 7, 3}, {2, 4, 8, 6}};
  for (int f = 0; f < 6; ++f) {
    if (f == skip_face) continue;
    const int* q = quads[f];
    text += "f " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) +
            "\n";
    text += "f " + std::to_string(q[0]) + " " + std::to_string(q[2]) + " " + std::to_string(q[3]) +
            "\n";
  }
  return text;
}

nlohmann::json ingest_with_cad(const io::testing::TempDir& dir, const std::string& obj_text) {
  io::testing::write_bundle(dir.path());
  io::testing::write_text(dir / "cad" / "hull.obj", obj_text);
  StageContext context;
  context.mission_dir = dir.path();
  context.cad_path = dir / "cad" / "hull.obj";
  return make_ingest_stage()->run(context).report;
}

bool has_warning(const nlohmann::json& report, const std::string& needle) {
  for (const auto& w : report["warnings"])
    if (w.get<std::string>().find(needle) != std::string::npos) return true;
  return false;
}

TEST(IngestStage, UnitCubeCadIsTwelveTrianglesOfAreaSixAndClosed) {
  TempDir dir;
  const auto r = ingest_with_cad(dir, cube_obj(1.0));
  const auto& cad = r["cad"];
  EXPECT_EQ(cad["file"], "hull.obj");
  EXPECT_EQ(cad["num_faces"], 12);
  EXPECT_EQ(cad["num_vertices"], 8);
  EXPECT_EQ(cad["num_edges"], 18);  // Euler: 8 - 18 + 12 = 2
  EXPECT_NEAR(cad["surface_area_m2"].get<double>(), 6.0, 1e-12);
  EXPECT_EQ(cad["bbox_min"], nlohmann::json({0.0, 0.0, 0.0}));
  EXPECT_EQ(cad["bbox_max"], nlohmann::json({1.0, 1.0, 1.0}));
  EXPECT_TRUE(cad["closed"].get<bool>());
  EXPECT_EQ(cad["boundary_edges"], 0);
  EXPECT_EQ(cad["non_manifold_edges"], 0);
  EXPECT_EQ(cad["degenerate_faces"], 0);
  EXPECT_EQ(cad["inconsistent_edges"], 0);
  EXPECT_TRUE(cad["warnings"].empty()) << cad.dump();
  EXPECT_FALSE(has_warning(r, "cad:")) << r["warnings"].dump();
}

TEST(IngestStage, CubeWithOneFaceRemovedHasFourBoundaryEdges) {
  TempDir dir;
  const auto r = ingest_with_cad(dir, cube_obj(1.0, /*skip_face=*/3));
  const auto& cad = r["cad"];
  EXPECT_EQ(cad["num_faces"], 10);
  EXPECT_NEAR(cad["surface_area_m2"].get<double>(), 5.0, 1e-12);
  EXPECT_EQ(cad["boundary_edges"], 4);
  EXPECT_FALSE(cad["closed"].get<bool>());
  EXPECT_TRUE(has_warning(r, "cad: 4 boundary edges")) << r["warnings"].dump();
}

TEST(IngestStage, CadInMillimetresOrKilometresIsFlagged) {
  TempDir dir;
  // A 30 m hull written in millimetres.
  auto r = ingest_with_cad(dir, cube_obj(30000.0));
  EXPECT_NEAR(r["cad"]["surface_area_m2"].get<double>(), 6 * 30000.0 * 30000.0, 1e-3);
  EXPECT_TRUE(has_warning(r, "millimetres")) << r["warnings"].dump();
  // A 200 m hull written in kilometres.
  r = ingest_with_cad(dir, cube_obj(0.2));
  EXPECT_TRUE(has_warning(r, "kilometres")) << r["warnings"].dump();
  // A 30 m hull in metres is not flagged.
  r = ingest_with_cad(dir, cube_obj(30.0));
  EXPECT_FALSE(has_warning(r, "cad:")) << r["warnings"].dump();
}

TEST(IngestStage, CadThatCannotServeIsRefusedNamingTheProblem) {
  TempDir dir;
  std::string nan_vertex = cube_obj(1.0);
  nan_vertex.replace(nan_vertex.find("v 1.000000"), 10, "v nan");
  io::testing::expect_error([&] { ingest_with_cad(dir, nan_vertex); },
                            {"hull.obj:2", "non-finite"});
  io::testing::expect_error([&] { ingest_with_cad(dir, "v 0 0 0\nv 1 0 0\nv 0 1 0\n"); },
                            {"hull.obj", "no faces"});
  io::testing::expect_error([&] { ingest_with_cad(dir, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"); },
                            {"hull.obj", "all 1 triangles are degenerate"});
}

}  // namespace
}  // namespace keel::pipeline
