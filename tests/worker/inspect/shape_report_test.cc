// Merging per-view shapes (Algorithm 1, seed 001) into objects for shapes.json.
#include "worker/inspect/shape_report.h"

#include <gtest/gtest.h>

namespace keel::inspect {
namespace {

DetectedShape detection(int view, std::vector<int> landmarks) {
  DetectedShape d;
  d.view = view;
  d.landmarks = std::move(landmarks);
  return d;
}

Landmark at(double x, double y, double z, double h) {
  Landmark l;
  l.point_world = Eigen::Vector3d(x, y, z);
  l.h_m = h;
  return l;
}

TEST(ShapeReport, MergesDetectionsThatShareFeatures) {
  std::vector<Landmark> landmarks;
  for (int i = 0; i < 8; ++i) landmarks.push_back(at(i, 0, 0.1, 0.1 + 0.01 * i));
  landmarks[6].h_m = -0.3;  // the largest magnitude, negative
  for (int i = 0; i < 3; ++i) landmarks.push_back(at(10, i, 0.2, 0.2));  // ids 8, 9, 10
  // Views 4 and 2 share feature 2, view 7 links to view 2 through feature 5; view 5 is apart.
  const std::vector<DetectedShape> detections = {detection(4, {0, 1, 2}), detection(5, {8, 9, 10}),
                                                 detection(2, {2, 3, 4, 5}),
                                                 detection(7, {5, 6, 7})};
  const std::vector<ShapeSummary> shapes = summarize_shapes(detections, landmarks, 0.12);
  ASSERT_EQ(shapes.size(), 2u);

  const ShapeSummary& a = shapes[0];
  EXPECT_EQ(a.id, 0);
  EXPECT_EQ(a.num_landmarks, 8);
  EXPECT_EQ(a.num_detections, 3);
  EXPECT_EQ(a.views, (std::vector<int>{2, 4, 7}));
  EXPECT_TRUE(a.centroid_world.isApprox(Eigen::Vector3d(3.5, 0, 0.1)));
  EXPECT_EQ(a.min_world, Eigen::Vector3d(0, 0, 0.1));
  EXPECT_EQ(a.max_world, Eigen::Vector3d(7, 0, 0.1));
  EXPECT_EQ(a.extent_m(), Eigen::Vector3d(7, 0, 0));
  double sum = -0.3;
  for (int i = 0; i < 8; ++i) sum += i == 6 ? 0.0 : 0.1 + 0.01 * i;
  EXPECT_NEAR(a.mean_deviation_m, sum / 8, 1e-12);
  EXPECT_EQ(a.max_deviation_m, -0.3);
  // |h| 0.3, 0.17, 0.15, 0.14, 0.13: four spacings (top_sampling.h)
  EXPECT_NEAR(a.height_sampling_sigma_m, (0.3 - 0.13) / 4, 1e-12);

  const ShapeSummary& b = shapes[1];
  EXPECT_EQ(b.id, 1);
  EXPECT_EQ(b.views, (std::vector<int>{5}));
  EXPECT_TRUE(b.centroid_world.isApprox(Eigen::Vector3d(10, 1, 0.2)));
  EXPECT_NEAR(b.mean_deviation_m, 0.2, 1e-12);
  EXPECT_EQ(b.height_sampling_sigma_m, 0.0);  // three features at the same height
}

TEST(ShapeReport, MergesDetectionsWhoseFeaturesAreClose) {
  // Two cameras saw disjoint halves of one object: no shared feature, but 0.05 m apart.
  std::vector<Landmark> landmarks;
  for (int i = 0; i < 6; ++i) landmarks.push_back(at(0.05 * i, 0, 0.1, 0.1));
  landmarks.push_back(at(3.0, 0, 0.1, 0.1));  // id 6, far away
  const std::vector<DetectedShape> detections = {detection(0, {0, 1, 2}), detection(1, {3, 4, 5}),
                                                 detection(2, {6})};
  const auto shapes = summarize_shapes(detections, landmarks, 0.12);
  ASSERT_EQ(shapes.size(), 2u);
  EXPECT_EQ(shapes[0].num_landmarks, 6);
  EXPECT_EQ(shapes[0].views, (std::vector<int>{0, 1}));
  EXPECT_EQ(shapes[1].views, (std::vector<int>{2}));
  // Below the gap, the halves stay apart.
  EXPECT_EQ(summarize_shapes(detections, landmarks, 0.04).size(), 3u);
}

TEST(ShapeReport, JsonCarriesEveryFieldAndTheOptions) {
  ShapeSummary s;
  s.id = 3;
  s.centroid_world = {1, 2, 3};
  s.min_world = {0.5, 1.5, 2.9};
  s.max_world = {1.5, 2.5, 3.1};
  s.mean_deviation_m = 0.1;
  s.max_deviation_m = 0.18;
  s.height_sampling_sigma_m = 0.02;
  s.num_landmarks = 12;
  s.num_detections = 4;
  s.views = {1, 5};
  InspectOptions options;
  options.tau_m = 0.0;
  const nlohmann::json doc = shapes_to_json({s}, options);
  EXPECT_EQ(doc.at("options").at("tau_m"), 0.0);
  EXPECT_EQ(doc.at("options").at("alpha_m"), 0.12);
  EXPECT_EQ(doc.at("options").at("dbscan_min_pts"), 3);
  EXPECT_EQ(doc.at("options").at("view_range_m"), 5.0);
  const nlohmann::json& j = doc.at("shapes").at(0);
  EXPECT_EQ(j.at("id"), 3);
  EXPECT_EQ(j.at("centroid_world_m"), nlohmann::json({1.0, 2.0, 3.0}));
  EXPECT_EQ(j.at("min_world_m"), nlohmann::json({0.5, 1.5, 2.9}));
  EXPECT_EQ(j.at("max_world_m"), nlohmann::json({1.5, 2.5, 3.1}));
  EXPECT_NEAR(j.at("extent_m")[2].get<double>(), 0.2, 1e-12);
  EXPECT_EQ(j.at("mean_deviation_m"), 0.1);
  EXPECT_EQ(j.at("max_deviation_m"), 0.18);
  EXPECT_EQ(j.at("height_sampling_sigma_m"), 0.02);
  EXPECT_EQ(j.at("num_landmarks"), 12);
  EXPECT_EQ(j.at("num_detections"), 4);
  EXPECT_EQ(j.at("views"), nlohmann::json({1, 5}));
  EXPECT_TRUE(shapes_to_json({}, options).at("shapes").empty());
}

}  // namespace
}  // namespace keel::inspect
