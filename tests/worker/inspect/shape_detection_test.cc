// Algorithm 1 of seed 001 (shape detection at one camera pose) on hand-built feature sets.
#include "worker/inspect/shape_detection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "tests/worker/inspect/synthetic_hull.h"

namespace keel::inspect {
namespace {

Landmark feature(double x, double y, double z) {
  Landmark l;
  l.point_world = Eigen::Vector3d(x, y, z);
  l.h_m = z;  // the prior is the plane z = 0
  l.views = {0};
  return l;
}

std::vector<int> all_indices(size_t n) {
  std::vector<int> ids(n);
  std::iota(ids.begin(), ids.end(), 0);
  return ids;
}

class ShapeDetection : public ::testing::Test {
 protected:
  void SetUp() override {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> plane(-0.9, 0.9), unit(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.005);
    for (int k = 0; k < 200; ++k) {  // the hull: |h| well below tau
      landmarks.push_back(feature(plane(rng), plane(rng), std::clamp(noise(rng), -0.015, 0.015)));
    }
    for (int k = 0; k < 40; ++k) {  // a 0.11 m object of radius 0.2 m at (0.3, -0.2)
      const double r = 0.2 * std::sqrt(unit(rng)), phi = 2 * M_PI * unit(rng);
      object.push_back(static_cast<int>(landmarks.size()));
      landmarks.push_back(feature(0.3 + r * std::cos(phi), -0.2 + r * std::sin(phi), 0.11));
    }
    // Two lone outliers (section 4.2.1: too few points for DBSCAN with minPts = 3).
    landmarks.push_back(feature(-0.7, 0.7, 0.18));
    landmarks.push_back(feature(-0.7, -0.7, 0.18));
  }

  const Pose3 T_world_camera = testing::camera_looking_down({0.1, 0.0}, 1.5);
  // detect_shapes() applies tau as given (run_inspect() raises it above the noise of h); 0.06 m
  // (Fig. 21(c)) clears the hull's |h| <= 0.015 m.
  const InspectOptions options = [] {
    InspectOptions o;
    o.tau_m = 0.06;
    return o;
  }();
  std::vector<Landmark> landmarks;
  std::vector<int> object;
};

TEST_F(ShapeDetection, FindsTheObjectAndIgnoresHullAndOutliers) {
  const auto shapes =
      detect_shapes(3, T_world_camera, landmarks, all_indices(landmarks.size()), options);
  ASSERT_EQ(shapes.size(), 1u);
  EXPECT_EQ(shapes[0].view, 3);
  EXPECT_EQ(shapes[0].landmarks, object);
  const Shape25d& shape = shapes[0].shape;
  ASSERT_FALSE(shape.mesh.faces.empty());
  const Pose3 T_camera_world = T_world_camera.inverse();
  for (size_t k = 0; k < shape.mesh.vertices.size(); ++k) {
    // Line 7 (points in the camera frame) and line 13 (lifted by the camera-relative z).
    const Eigen::Vector3d expected = T_camera_world * landmarks[shape.source_index[k]].point_world;
    EXPECT_NEAR((shape.mesh.vertices[k] - expected).norm(), 0.0, 1e-12);
    EXPECT_NEAR(shape.mesh.vertices[k].z(), 1.5 - 0.11, 1e-12);
  }
}

TEST_F(ShapeDetection, TauAboveTheObjectHeightLeavesNothing) {
  InspectOptions high = options;
  high.tau_m = 0.2;  // line 6: |h| must exceed tau
  EXPECT_TRUE(
      detect_shapes(0, T_world_camera, landmarks, all_indices(landmarks.size()), high).empty());
}

TEST_F(ShapeDetection, OnlyVisibleFeaturesCount) {
  std::vector<int> visible;  // everything but the object
  for (int i = 0; i < static_cast<int>(landmarks.size()); ++i) {
    if (std::find(object.begin(), object.end(), i) == object.end()) visible.push_back(i);
  }
  EXPECT_TRUE(detect_shapes(0, T_world_camera, landmarks, visible, options).empty());
}

TEST(ShapeDetectionSpace, ClustersOverImageXyAndDeviation) {
  // Line 8 clusters (f_x, f_y, d): two objects overlapping in the image but 0.3 m apart in
  // deviation are two clusters, hence two shapes.
  std::vector<Landmark> landmarks;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      landmarks.push_back(feature(0.05 * i, 0.05 * j, 0.1));
      landmarks.push_back(feature(0.05 * i + 0.025, 0.05 * j + 0.025, 0.4));
    }
  }
  const auto shapes = detect_shapes(0, testing::camera_looking_down({0, 0}, 1.5), landmarks,
                                    all_indices(landmarks.size()), {});
  ASSERT_EQ(shapes.size(), 2u);
  for (const auto& shape : shapes) {
    EXPECT_EQ(shape.landmarks.size(), 36u);
    const double h = landmarks[shape.landmarks[0]].h_m;
    for (const int id : shape.landmarks) EXPECT_EQ(landmarks[id].h_m, h);
  }
}

TEST(ShapeDetectionSpace, FeaturesBehindTheCameraAreSkipped) {
  std::vector<Landmark> landmarks;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) landmarks.push_back(feature(0.05 * i, 0.05 * j, 2.0));
  }
  // The camera at 1.5 m looks down; these features are above it.
  EXPECT_TRUE(detect_shapes(0, testing::camera_looking_down({0, 0}, 1.5), landmarks,
                            all_indices(landmarks.size()), {})
                  .empty());
}

}  // namespace
}  // namespace keel::inspect
