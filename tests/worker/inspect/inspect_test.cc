// Algorithms 1 + 2 and Eq. (15) of seed 001 end to end on a flat CAD patch with synthetic
// objects of known height, seen from several downward-looking cameras.
#include "worker/inspect/inspect.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "tests/worker/inspect/synthetic_hull.h"

namespace keel::inspect {
namespace {

using testing::Bump;
using testing::SceneOptions;

// A 4 m x 4 m patch (5 cm grid) and a 3 x 3 grid of cameras 1.5 m above, +-0.5 m around the
// origin: every camera sees the whole 0.6 m object at the origin.
SceneOptions patch_with_cameras() {
  SceneOptions options;
  for (const double x : {-0.5, 0.0, 0.5}) {
    for (const double y : {-0.5, 0.0, 0.5}) options.camera_xy.emplace_back(x, y);
  }
  return options;
}

double radius_xy(const Eigen::Vector3d& v) { return v.head<2>().norm(); }

void expect_invalid(const InspectInput& input, const InspectOptions& options,
                    const std::string& fragment) {
  try {
    run_inspect(input, options);
    FAIL() << "expected std::invalid_argument mentioning " << fragment;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(Inspect, CylinderBumpIsFusedIntoTheMesh) {
  SceneOptions scene = patch_with_cameras();
  const Bump bump{{0.0, 0.0}, 0.3, 0.11, 80};
  scene.bumps = {bump};
  InspectInput input = testing::make_scene(scene);
  input.cad_in_world.vertex_normals.assign(input.cad_in_world.num_vertices(), {0, 0, 1});
  const InspectResult result = run_inspect(input);

  ASSERT_EQ(result.remeshed.vertices.size(), input.cad_in_world.vertices.size());
  EXPECT_FALSE(result.remeshed.has_vertex_normals());  // stale once vertices moved
  EXPECT_EQ(result.remeshed.faces, input.cad_in_world.faces);
  int over_bump = 0;
  for (size_t i = 0; i < input.cad_in_world.vertices.size(); ++i) {
    const Eigen::Vector3d& prior = input.cad_in_world.vertices[i];
    const Eigen::Vector3d& fused = result.remeshed.vertices[i];
    const double r = radius_xy(prior);
    if (r < bump.radius_m - 0.1) {  // well inside the object's top
      ++over_bump;
      EXPECT_NEAR(fused.z(), bump.height_m, 0.015) << "vertex " << i << " at r = " << r;
      EXPECT_NEAR(result.vertex_deviation_m[i], bump.height_m, 0.015);
      EXPECT_GE(result.vertex_update_count[i], 1);
      // Near the centre every camera's ray meets the shape (rays cross the top <= 0.07 m from
      // the vertex); farther out the alpha shape's ragged rim may miss a slanted ray.
      if (r < 0.1) {
        EXPECT_EQ(result.vertex_update_count[i], 9) << "vertex " << i;
      }
    } else if (r > bump.radius_m + 0.2) {
      // Beyond the rim: camera rays pass the object's top no farther than ~0.08 m out (the
      // top is 0.11 m up, the cameras 1.5 m up and <= ~0.7 m away sideways).
      EXPECT_EQ(fused, prior) << "vertex " << i;
      EXPECT_EQ(result.vertex_deviation_m[i], 0.0);
      EXPECT_EQ(result.vertex_update_count[i], 0);
    }
  }
  EXPECT_GT(over_bump, 40);  // 0.05 m grid: ~pi 0.2^2 / 0.05^2 = 50 vertices

  ASSERT_EQ(result.shapes.size(), 1u);
  const ShapeSummary& shape = result.shapes[0];
  EXPECT_LT(shape.centroid_world.head<2>().norm(), 0.05);
  EXPECT_NEAR(shape.centroid_world.z(), bump.height_m, 0.005);
  EXPECT_NEAR(shape.mean_deviation_m, bump.height_m, 0.005);
  EXPECT_NEAR(shape.max_deviation_m, bump.height_m, 0.01);
  EXPECT_LE(shape.extent_m().x(), 2 * bump.radius_m);
  EXPECT_GT(shape.extent_m().x(), 1.5 * bump.radius_m);
  EXPECT_EQ(shape.num_landmarks, bump.num_landmarks);
  EXPECT_EQ(shape.num_detections, 9);
  EXPECT_EQ(shape.views, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(result.stats.num_detections, 9);
  EXPECT_EQ(result.stats.num_views_with_shapes, 9);
}

// min_shape_views: the bump's features matched in one or two views only (as three noisy
// features can agree in one view) make no shape and move no vertex; in three views they do.
TEST(Inspect, ShapeSeenInFewerThanMinShapeViewsIsDroppedBeforeFusion) {
  SceneOptions scene = patch_with_cameras();
  scene.bumps = {Bump{{0.0, 0.0}, 0.3, 0.11, 80}};
  InspectInput input = testing::make_scene(scene);
  auto seen_in = [&](const std::vector<int>& views) {
    for (Landmark& l : input.landmarks)
      if (l.h_m > 0.05) l.views = views;
    return run_inspect(input);
  };
  for (const std::vector<int>& views : {std::vector<int>{4}, std::vector<int>{2, 6}}) {
    const InspectResult result = seen_in(views);
    EXPECT_TRUE(result.shapes.empty()) << views.size() << " views";
    EXPECT_TRUE(result.detections.empty());
    EXPECT_EQ(result.stats.num_detections, static_cast<int>(views.size()));
    EXPECT_EQ(result.stats.num_shapes_rejected, 1);
    EXPECT_EQ(result.stats.num_views_with_shapes, 0);
    EXPECT_EQ(result.remeshed.vertices, input.cad_in_world.vertices);
  }
  const InspectResult three = seen_in({1, 4, 7});
  ASSERT_EQ(three.shapes.size(), 1u);
  EXPECT_EQ(three.shapes[0].views, (std::vector<int>{1, 4, 7}));
  EXPECT_EQ(three.shapes[0].detections, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(three.stats.num_shapes_rejected, 0);
  EXPECT_NE(three.remeshed.vertices, input.cad_in_world.vertices);
  InspectOptions every_detection;  // the paper: no such rule
  every_detection.min_shape_views = 1;
  for (Landmark& l : input.landmarks)
    if (l.h_m > 0.05) l.views = {4};
  EXPECT_EQ(run_inspect(input, every_detection).shapes.size(), 1u);
}

TEST(Inspect, CleanPatchReportsNothingAndKeepsTheMesh) {
  SceneOptions scene = patch_with_cameras();
  scene.num_hull_landmarks = 1500;
  scene.hull_noise_m = 0.015;  // clipped at 3 sigma = 0.045 m < tau ~ 8 sigma
  InspectInput input = testing::make_scene(scene);
  input.cad_in_world.vertex_normals.assign(input.cad_in_world.num_vertices(), {0, 0, 1});
  const InspectResult result = run_inspect(input);
  EXPECT_EQ(result.remeshed.vertex_normals, input.cad_in_world.vertex_normals);
  EXPECT_TRUE(result.shapes.empty());
  EXPECT_TRUE(result.detections.empty());
  EXPECT_EQ(result.remeshed.vertices, input.cad_in_world.vertices);
  for (size_t i = 0; i < result.vertex_deviation_m.size(); ++i) {
    EXPECT_EQ(result.vertex_deviation_m[i], 0.0);
    EXPECT_EQ(result.vertex_update_count[i], 0);
  }
}

TEST(Inspect, LowBumpAboveTheHullNoiseIsFoundWithTheDefaultTau) {
  // A 4 cm biofouling-like bump: inside the max-mixture's lambda = 1 basin and below the
  // paper's false-positive setting tau = 0.06 m, but 10 noise sigmas above clean hull (4 mm,
  // clipped at 3 sigma). The default tau (8 noise sigmas, deviation_threshold.h) finds it;
  // tau = 0.06 m does not.
  SceneOptions scene = patch_with_cameras();
  scene.num_hull_landmarks = 1500;
  scene.hull_noise_m = 0.004;
  scene.bump_noise_m = 0.002;
  scene.bumps = {Bump{{0.0, 0.0}, 0.2, 0.04, 30}};
  const InspectInput input = testing::make_scene(scene);
  const InspectResult result = run_inspect(input);
  EXPECT_NEAR(result.threshold.noise_sigma_m, 0.004, 0.0008);
  ASSERT_EQ(result.shapes.size(), 1u);
  EXPECT_LT(radius_xy(result.shapes[0].centroid_world), 0.05);
  EXPECT_NEAR(result.shapes[0].mean_deviation_m, 0.04, 0.003);
  // DBSCAN may leave an isolated rim feature out; no hull feature (|h| <= 1.2 cm) joins.
  EXPECT_GE(result.shapes[0].num_landmarks, 25);
  EXPECT_LE(result.shapes[0].num_landmarks, 30);

  InspectOptions paper_false_positive_setting;
  paper_false_positive_setting.tau_m = 0.06;
  EXPECT_TRUE(run_inspect(input, paper_false_positive_setting).shapes.empty());
}

TEST(Inspect, MovingAverageOfEq15IsTheMeanOfTheIntersections) {
  // A flat plate 0.2 m above the patch sampled on an exact grid (no noise): every view's shape
  // lies in the plane z = 0.2, so the ray camera -> vertex meets it at c + t (v - c) with
  // t = (0.2 - c_z) / (v_z - c_z). Eq. (15) starts from v_0 with n = 0, so after N views the
  // vertex is the mean of the N intersections (the prior vertex itself gets no weight).
  SceneOptions scene = patch_with_cameras();
  scene.num_hull_landmarks = 0;
  InspectInput input = testing::make_scene(scene);
  for (int i = -6; i <= 6; ++i) {
    for (int j = -6; j <= 6; ++j) {
      Landmark l;
      l.point_world = Eigen::Vector3d(0.05 * i + 0.01, 0.05 * j + 0.02, 0.2);
      l.h_m = 0.2;
      l.views = {0, 1, 2, 3, 4, 5, 6, 7, 8};
      input.landmarks.push_back(l);
    }
  }
  const InspectResult result = run_inspect(input);
  int checked = 0;
  for (size_t i = 0; i < input.cad_in_world.vertices.size(); ++i) {
    const Eigen::Vector3d& v = input.cad_in_world.vertices[i];
    if (v.head<2>().cwiseAbs().maxCoeff() > 0.15) continue;  // inside every view's footprint
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Pose3& T : input.T_world_camera) {
      const Eigen::Vector3d c = T.translation();
      mean += c + (0.2 - c.z()) / (v.z() - c.z()) * (v - c);
    }
    mean /= static_cast<double>(input.T_world_camera.size());
    EXPECT_EQ(result.vertex_update_count[i], 9);
    EXPECT_NEAR((result.remeshed.vertices[i] - mean).norm(), 0.0, 1e-9) << "vertex " << i;
    EXPECT_NEAR(result.vertex_deviation_m[i], 0.2, 1e-9);
    ++checked;
  }
  EXPECT_GT(checked, 30);
}

TEST(Inspect, DentsNeedRaysThatContinueBehindTheVertex) {
  SceneOptions scene = patch_with_cameras();
  scene.bumps = {Bump{{0.0, 0.0}, 0.3, -0.1, 80}};
  const InspectInput input = testing::make_scene(scene);
  // The paper's segment camera -> vertex (section 3.3) never reaches structure behind the CAD
  // surface: the dent is detected (Algorithm 1) but nothing moves.
  const InspectResult segment = run_inspect(input);
  EXPECT_EQ(segment.shapes.size(), 1u);
  EXPECT_EQ(segment.remeshed.vertices, input.cad_in_world.vertices);
  InspectOptions options;
  options.max_behind_vertex_m = 0.5;
  const InspectResult ray = run_inspect(input, options);
  int inside = 0;
  for (size_t i = 0; i < input.cad_in_world.vertices.size(); ++i) {
    if (radius_xy(input.cad_in_world.vertices[i]) >= 0.2) continue;
    ++inside;
    EXPECT_NEAR(ray.remeshed.vertices[i].z(), -0.1, 0.015);
    EXPECT_NEAR(ray.vertex_deviation_m[i], -0.1, 0.015);
  }
  EXPECT_GT(inside, 40);
}

TEST(Inspect, OnlyVerticesWithinViewRangeMove) {
  SceneOptions scene = patch_with_cameras();
  scene.bumps = {Bump{{0.0, 0.0}, 0.3, 0.11, 80}};
  const InspectInput input = testing::make_scene(scene);
  InspectOptions options;
  options.view_range_m = 1.4;  // the cameras are 1.5 m above the patch
  const InspectResult result = run_inspect(input, options);
  EXPECT_EQ(result.shapes.size(), 1u);
  EXPECT_EQ(result.stats.num_vertices_moved, 0);
  EXPECT_EQ(result.remeshed.vertices, input.cad_in_world.vertices);
}

TEST(Inspect, TwoObjectsGiveTwoShapes) {
  SceneOptions scene;
  scene.nx = scene.ny = 121;  // 6 m x 6 m
  for (const double x : {-1.5, -1.0, 1.0, 1.5}) {
    for (const double y : {-0.5, 0.0, 0.5}) scene.camera_xy.emplace_back(x, y);
  }
  scene.bumps = {Bump{{-1.2, 0.0}, 0.25, 0.11, 60}, Bump{{1.2, 0.0}, 0.3, 0.15, 60}};
  const InspectResult result = run_inspect(testing::make_scene(scene));
  ASSERT_EQ(result.shapes.size(), 2u);
  EXPECT_NEAR(result.shapes[0].centroid_world.x(), -1.2, 0.05);
  EXPECT_NEAR(result.shapes[0].mean_deviation_m, 0.11, 0.005);
  EXPECT_NEAR(result.shapes[1].centroid_world.x(), 1.2, 0.05);
  EXPECT_NEAR(result.shapes[1].mean_deviation_m, 0.15, 0.005);
  // Cameras 0-5 at x = -1.5, -1.0 see only the first object, 6-11 only the second.
  EXPECT_EQ(result.shapes[0].views, (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(result.shapes[1].views, (std::vector<int>{6, 7, 8, 9, 10, 11}));
}

TEST(Inspect, BadInputNamesTheField) {
  SceneOptions scene = patch_with_cameras();
  scene.num_hull_landmarks = 10;
  const InspectInput good = testing::make_scene(scene);
  const double nan = std::numeric_limits<double>::quiet_NaN();

  InspectInput input = good;
  input.landmarks[3].views = {9};
  expect_invalid(input, {}, "landmarks[3].views[0]");
  input = good;
  input.landmarks[2].views = {1, 1};
  expect_invalid(input, {}, "landmarks[2].views");
  input = good;
  input.landmarks[4].h_m = nan;
  expect_invalid(input, {}, "landmarks[4].h_m");
  input = good;
  input.landmarks[5].point_world.x() = nan;
  expect_invalid(input, {}, "landmarks[5].point_world");
  input = good;
  input.T_world_camera[1].linear() *= 2.0;
  expect_invalid(input, {}, "T_world_camera[1]");
  input = good;
  input.cad_in_world.faces[7] = Eigen::Vector3i(0, 1, 1000000);
  expect_invalid(input, {}, "cad_in_world.faces[7]");
  input = good;
  input.cad_in_world.faces.clear();
  expect_invalid(input, {}, "cad_in_world.faces");

  InspectOptions options;
  options.tau_m = -0.1;
  expect_invalid(good, options, "tau_m");
  options = {};
  options.alpha_m = 0.0;
  expect_invalid(good, options, "alpha_m");
  options = {};
  options.dbscan_min_pts = 0;
  expect_invalid(good, options, "dbscan_min_pts");
  options = {};
  options.min_shape_views = 0;
  expect_invalid(good, options, "min_shape_views");
  options = {};
  options.view_range_m = nan;
  expect_invalid(good, options, "view_range_m");
  options = {};
  options.top_site_noise_sigmas = -1.0;
  expect_invalid(good, options, "top_site_noise_sigmas");
  options = {};
  options.top_spacings = 0;
  expect_invalid(good, options, "top_spacings");
}

}  // namespace
}  // namespace keel::inspect
