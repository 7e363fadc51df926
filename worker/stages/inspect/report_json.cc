#include "worker/stages/inspect/report_json.h"

namespace keel::pipeline {

nlohmann::json inspect_report(const BaSolution& solution, const inspect::InspectResult& result,
                              const nlohmann::json& draco, const InspectStageOptions& options) {
  nlohmann::json r;
  r["solution_mode"] = solution.mode;
  r["options"] = options.inspect.to_json();
  r["tau_m"] = result.threshold.tau_m;  // line 6 of Algorithm 1, after the noise floor
  r["deviation_noise_sigma_m"] = result.threshold.noise_sigma_m;
  r["deviation_bias_m"] = result.threshold.bias_m;
  r["views"] = result.stats.num_views;
  r["views_with_shapes"] = result.stats.num_views_with_shapes;
  r["detections"] = result.stats.num_detections;
  r["shapes_rejected_few_views"] = result.stats.num_shapes_rejected;
  r["updates"] = result.stats.num_updates;
  r["vertices_moved"] = result.stats.num_vertices_moved;
  r["detect_s"] = result.stats.detect_s;
  r["fuse_s"] = result.stats.fuse_s;
  r["deviation_s"] = result.stats.deviation_s;
  r["draco"] = draco;
  nlohmann::json shapes = nlohmann::json::array();
  for (const auto& s : result.shapes)
    shapes.push_back(
        {{"id", s.id},
         {"height_m", s.max_deviation_m},
         {"mean_deviation_m", s.mean_deviation_m},
         {"centroid_world", {s.centroid_world.x(), s.centroid_world.y(), s.centroid_world.z()}},
         {"extent_m", {s.extent_m().x(), s.extent_m().y(), s.extent_m().z()}},
         {"views", s.views.size()},
         {"landmarks", s.num_landmarks},
         {"detections", s.num_detections}});
  r["shapes"] = shapes;
  return r;
}

}  // namespace keel::pipeline
