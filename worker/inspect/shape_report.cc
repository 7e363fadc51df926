#include "worker/inspect/shape_report.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>

#include "worker/inspect/radius_index.h"

namespace keel::inspect {
namespace {

nlohmann::json vector_json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];  // path halving
    i = parent[i];
  }
  return i;
}

void unite(std::vector<int>& parent, int a, int b) {
  a = find_root(parent, a);
  b = find_root(parent, b);
  parent[std::max(a, b)] = std::min(a, b);  // the root stays the earliest detection
}

// Object of each detection: connected components of "shares a feature, or has a feature within
// link_distance_m of one of the other's features".
std::vector<int> group_detections(const std::vector<DetectedShape>& detections,
                                  const std::vector<Landmark>& landmarks, double link_distance_m) {
  std::vector<int> parent(detections.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::unordered_map<int, int> node_of_landmark;  // feature id -> index into first_detection
  std::vector<int> first_detection;
  std::vector<Eigen::Vector3d> points_world;
  for (size_t k = 0; k < detections.size(); ++k) {
    for (const int id : detections[k].landmarks) {
      const auto [it, inserted] =
          node_of_landmark.emplace(id, static_cast<int>(first_detection.size()));
      if (inserted) {
        first_detection.push_back(static_cast<int>(k));
        points_world.push_back(landmarks[id].point_world);
      } else {
        unite(parent, first_detection[it->second], static_cast<int>(k));
      }
    }
  }
  const RadiusIndex index(points_world);
  std::vector<int> near;
  for (size_t node = 0; node < points_world.size(); ++node) {
    index.within(points_world[node], link_distance_m, &near);
    for (const int other : near) unite(parent, first_detection[node], first_detection[other]);
  }
  for (size_t k = 0; k < detections.size(); ++k) parent[k] = find_root(parent, static_cast<int>(k));
  return parent;
}

ShapeSummary summarize(const std::vector<int>& landmark_ids, const std::vector<int>& views,
                       int num_detections, const std::vector<Landmark>& landmarks,
                       const TopSampling& top) {
  ShapeSummary s;
  s.min_world.setConstant(std::numeric_limits<double>::infinity());
  s.max_world = -s.min_world;
  for (const int id : landmark_ids) {
    const Landmark& l = landmarks[id];
    s.centroid_world += l.point_world;
    s.min_world = s.min_world.cwiseMin(l.point_world);
    s.max_world = s.max_world.cwiseMax(l.point_world);
    s.mean_deviation_m += l.h_m;
    if (std::abs(l.h_m) > std::abs(s.max_deviation_m)) s.max_deviation_m = l.h_m;
  }
  std::vector<double> abs_heights_m;
  abs_heights_m.reserve(landmark_ids.size());
  for (const int id : landmark_ids) abs_heights_m.push_back(std::abs(landmarks[id].h_m));
  s.height_sampling_sigma_m = top_sampling_sigma(std::move(abs_heights_m), top);
  const double n = static_cast<double>(landmark_ids.size());
  s.centroid_world /= n;
  s.mean_deviation_m /= n;
  s.num_landmarks = static_cast<int>(landmark_ids.size());
  s.num_detections = num_detections;
  s.views = views;
  return s;
}

}  // namespace

nlohmann::json ShapeSummary::to_json() const {
  return {{"id", id},
          {"centroid_world_m", vector_json(centroid_world)},
          {"min_world_m", vector_json(min_world)},
          {"max_world_m", vector_json(max_world)},
          {"extent_m", vector_json(extent_m())},
          {"mean_deviation_m", mean_deviation_m},
          {"max_deviation_m", max_deviation_m},
          {"height_sampling_sigma_m", height_sampling_sigma_m},
          {"num_landmarks", num_landmarks},
          {"num_detections", num_detections},
          {"views", views}};
}

std::vector<ShapeSummary> summarize_shapes(const std::vector<DetectedShape>& detections,
                                           const std::vector<Landmark>& landmarks,
                                           double link_distance_m, const TopSampling& top) {
  const std::vector<int> root = group_detections(detections, landmarks, link_distance_m);
  std::unordered_map<int, int> object_of_root;
  std::vector<std::vector<int>> object_landmarks, object_views;
  std::vector<std::vector<int>> object_detection_indices;
  for (size_t k = 0; k < detections.size(); ++k) {
    const auto [it, inserted] =
        object_of_root.emplace(root[k], static_cast<int>(object_landmarks.size()));
    if (inserted) {
      object_landmarks.emplace_back();
      object_views.emplace_back();
      object_detection_indices.emplace_back();
    }
    const int object = it->second;
    auto& ids = object_landmarks[object];
    ids.insert(ids.end(), detections[k].landmarks.begin(), detections[k].landmarks.end());
    object_views[object].push_back(detections[k].view);
    object_detection_indices[object].push_back(static_cast<int>(k));
  }
  std::vector<ShapeSummary> shapes;
  for (size_t o = 0; o < object_landmarks.size(); ++o) {
    for (auto* list : {&object_landmarks[o], &object_views[o]}) {
      std::sort(list->begin(), list->end());
      list->erase(std::unique(list->begin(), list->end()), list->end());
    }
    shapes.push_back(summarize(object_landmarks[o], object_views[o],
                               static_cast<int>(object_detection_indices[o].size()), landmarks,
                               top));
    shapes.back().id = static_cast<int>(o);
    shapes.back().detections = std::move(object_detection_indices[o]);
  }
  return shapes;
}

nlohmann::json shapes_to_json(const std::vector<ShapeSummary>& shapes,
                              const InspectOptions& options) {
  nlohmann::json list = nlohmann::json::array();
  for (const ShapeSummary& shape : shapes) list.push_back(shape.to_json());
  return {{"options", options.to_json()}, {"shapes", std::move(list)}};
}

}  // namespace keel::inspect
