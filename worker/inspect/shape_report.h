// The shapes list of shapes.json. Algorithm 1 (seed 001) finds shapes per camera view, so "a
// single physical object on the hull will have multiple shapes associated with it" (section
// 3.2); here those detections are merged into one object and summarised.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <vector>

#include "worker/inspect/inspect_input.h"
#include "worker/inspect/inspect_options.h"
#include "worker/inspect/shape_detection.h"
#include "worker/inspect/top_sampling.h"

namespace keel::inspect {

struct ShapeSummary {
  int id = 0;  // 0..k-1, in the order of each object's first detection
  // Over the object's features (the union of its detections' DBSCAN clusters), world frame:
  Eigen::Vector3d centroid_world = Eigen::Vector3d::Zero();  // mean position
  Eigen::Vector3d min_world = Eigen::Vector3d::Zero();       // axis-aligned bounds
  Eigen::Vector3d max_world = Eigen::Vector3d::Zero();
  double mean_deviation_m = 0.0;  // mean of h (Eq. 5), signed
  double max_deviation_m = 0.0;   // the h of largest magnitude, signed
  // How far the object's top may lie beyond max_deviation_m for want of a feature there: the
  // mean spacing of its highest features' heights (top_sampling.h), 0 when they all share one
  // height. On keel-sim's patches the highest feature was 0.2-3.7 cm below the top, against a
  // deviation noise of ~1 mm, so this dominates a height's error.
  double height_sampling_sigma_m = 0.0;
  int num_landmarks = 0;
  int num_detections = 0;       // per-view shapes merged into this object
  std::vector<int> views;       // views whose Algorithm 1 detected it, ascending
  std::vector<int> detections;  // indices of its detections in the list summarised, ascending

  Eigen::Vector3d extent_m() const { return max_world - min_world; }
  nlohmann::json to_json() const;
};

// Merges detections (transitively) that share a feature or come within link_distance_m of each
// other (world frame, feature to feature), and summarises each object. Sharing alone would
// split an object whose parts two cameras saw without overlap; run_inspect() links at
// dbscan_eps_m, the spacing DBSCAN itself accepts inside a cluster. `top` sets
// height_sampling_sigma_m.
std::vector<ShapeSummary> summarize_shapes(const std::vector<DetectedShape>& detections,
                                           const std::vector<Landmark>& landmarks,
                                           double link_distance_m, const TopSampling& top = {});

// The shapes.json document: {"options": ..., "shapes": [...]}.
nlohmann::json shapes_to_json(const std::vector<ShapeSummary>& shapes,
                              const InspectOptions& options);

}  // namespace keel::inspect
