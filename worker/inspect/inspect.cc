#include "worker/inspect/inspect.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "worker/inspect/mesh_fusion.h"
#include "worker/inspect/vertex_deviation.h"

namespace keel::inspect {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void require(bool ok, const std::string& option, double value, const std::string& expected) {
  if (!ok) {
    throw std::invalid_argument("inspect options: " + option + " = " + std::to_string(value) +
                                "; expected " + expected);
  }
}

// is_visible() of Algorithm 2, line 3: the features each view observed.
std::vector<std::vector<int>> visible_per_view(const InspectInput& input) {
  std::vector<std::vector<int>> visible(input.T_world_camera.size());
  for (size_t i = 0; i < input.landmarks.size(); ++i) {
    for (const int view : input.landmarks[i].views) visible[view].push_back(static_cast<int>(i));
  }
  return visible;
}

}  // namespace

void validate(const InspectOptions& o) {
  require(std::isfinite(o.tau_m) && o.tau_m >= 0.0, "tau_m", o.tau_m, "a finite value >= 0 m");
  require(std::isfinite(o.tau_noise_sigmas) && o.tau_noise_sigmas >= 0.0, "tau_noise_sigmas",
          o.tau_noise_sigmas, "a finite value >= 0");
  require(std::isfinite(o.dbscan_eps_m) && o.dbscan_eps_m > 0.0, "dbscan_eps_m", o.dbscan_eps_m,
          "a finite radius > 0 m");
  require(o.dbscan_min_pts >= 1, "dbscan_min_pts", o.dbscan_min_pts, "an integer >= 1");
  require(o.min_shape_views >= 1, "min_shape_views", o.min_shape_views, "an integer >= 1");
  require(std::isfinite(o.alpha_m) && o.alpha_m > 0.0, "alpha_m", o.alpha_m,
          "a finite radius > 0 m");
  require(std::isfinite(o.view_range_m) && o.view_range_m > 0.0, "view_range_m", o.view_range_m,
          "a finite range > 0 m");
  require(std::isfinite(o.max_behind_vertex_m) && o.max_behind_vertex_m >= 0.0,
          "max_behind_vertex_m", o.max_behind_vertex_m, "a finite value >= 0 m");
  require(std::isfinite(o.top_site_noise_sigmas) && o.top_site_noise_sigmas >= 0.0,
          "top_site_noise_sigmas", o.top_site_noise_sigmas, "a finite value >= 0");
  require(o.top_spacings >= 1, "top_spacings", o.top_spacings, "an integer >= 1");
}

InspectResult run_inspect(const InspectInput& input, const InspectOptions& options) {
  validate(options);
  validate(input);
  InspectResult result;
  InspectStats& stats = result.stats;
  stats.num_views = static_cast<int>(input.T_world_camera.size());
  const std::vector<std::vector<int>> visible = visible_per_view(input);
  result.threshold = deviation_threshold(input.landmarks, options);
  InspectOptions detection = options;  // line 6 of Algorithm 1 with the tau in force
  detection.tau_m = result.threshold.tau_m;

  // Algorithm 1 at every view first (line 4 of Algorithm 2), so that the detections can be
  // merged into objects and those seen in fewer than min_shape_views views dropped before
  // any is fused.
  auto start = Clock::now();
  std::vector<DetectedShape> all;
  for (int view = 0; view < stats.num_views; ++view) {
    std::vector<DetectedShape> shapes =
        detect_shapes(view, input.T_world_camera[view], input.landmarks, visible[view], detection);
    for (DetectedShape& shape : shapes) all.push_back(std::move(shape));
  }
  stats.num_detections = static_cast<int>(all.size());
  const TopSampling top{options.top_site_noise_sigmas * result.threshold.noise_sigma_m,
                        options.top_spacings};
  std::vector<ShapeSummary> objects =
      summarize_shapes(all, input.landmarks, options.dbscan_eps_m, top);
  std::vector<bool> kept(all.size(), false);
  for (const ShapeSummary& object : objects) {
    if (static_cast<int>(object.views.size()) < options.min_shape_views) {
      ++stats.num_shapes_rejected;
      continue;
    }
    for (const int k : object.detections) kept[k] = true;
    result.shapes.push_back(object);
    result.shapes.back().id = static_cast<int>(result.shapes.size()) - 1;
  }
  std::vector<int> new_index(all.size(), -1);  // into result.detections
  for (size_t k = 0; k < all.size(); ++k) {
    if (!kept[k]) continue;
    new_index[k] = static_cast<int>(result.detections.size());
    result.detections.push_back(std::move(all[k]));
  }
  for (ShapeSummary& object : result.shapes)
    for (int& k : object.detections) k = new_index[k];
  std::vector<std::vector<DetectedShape>> per_view(stats.num_views);
  for (const DetectedShape& shape : result.detections) per_view[shape.view].push_back(shape);
  stats.detect_s = seconds_since(start);

  MeshFusion fusion(input.cad_in_world, options);       // line 1 of Algorithm 2
  for (int view = 0; view < stats.num_views; ++view) {  // line 2
    start = Clock::now();
    stats.num_updates += fusion.fuse_view(input.T_world_camera[view], per_view[view]);  // 5-14
    stats.fuse_s += seconds_since(start);
    if (!per_view[view].empty()) ++stats.num_views_with_shapes;
  }
  result.remeshed = fusion.mesh();  // line 16
  result.vertex_update_count = fusion.update_counts();
  for (const int n : result.vertex_update_count) stats.num_vertices_moved += n > 0 ? 1 : 0;

  start = Clock::now();
  result.vertex_deviation_m =
      vertex_deviations(input.cad_in_world, result.remeshed, result.vertex_update_count);
  stats.deviation_s = seconds_since(start);
  return result;
}

}  // namespace keel::inspect
