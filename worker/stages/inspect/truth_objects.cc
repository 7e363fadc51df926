#include "worker/stages/inspect/truth_objects.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "proto/contract_error.h"
#include "worker/io/yaml_json.h"

namespace keel::pipeline {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct TruthObject {
  std::string kind;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius_m = 0, height_m = 0;
};

std::vector<TruthObject> truth_objects(const fs::path& truth_path) {
  const json truth = io::load_yaml_file(truth_path);
  std::vector<TruthObject> out;
  if (!truth.contains("foreign_objects")) return out;
  const json& list = truth["foreign_objects"];
  if (!list.is_array())
    throw std::runtime_error(truth_path.string() + ": foreign_objects: expected a list");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string path = truth_path.string() + ": foreign_objects[" + std::to_string(i) + "]";
    proto::FieldReader r(list[i], path);
    TruthObject o;
    o.kind = r.required<std::string>("kind");
    const json& c = r.at("center");
    if (!c.is_array() || c.size() != 3 || !c[0].is_number() || !c[1].is_number() ||
        !c[2].is_number())
      throw std::runtime_error(path + ".center: expected 3 numbers");
    o.center = Eigen::Vector3d(c[0].get<double>(), c[1].get<double>(), c[2].get<double>());
    o.radius_m = r.required<double>("radius");
    o.height_m = r.required<double>("height");
    out.push_back(o);
  }
  return out;
}

json evaluate_objects(const std::vector<TruthObject>& objects,
                      const std::vector<inspect::ShapeSummary>& shapes, double match_distance_m) {
  std::vector<bool> shape_matched(shapes.size(), false);
  json list = json::array();
  int found = 0;
  for (const auto& o : objects) {
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (size_t s = 0; s < shapes.size(); ++s) {
      const double d = (shapes[s].centroid_world - o.center).norm();
      if (d < best_d) best_d = d, best = int(s);
    }
    json entry = {{"kind", o.kind}, {"radius_m", o.radius_m}, {"true_height_m", o.height_m}};
    const bool hit = best >= 0 && best_d <= o.radius_m + match_distance_m;
    entry["found"] = hit;
    if (best >= 0) entry["nearest_shape_distance_m"] = best_d;
    if (hit) {
      ++found;
      shape_matched[best] = true;
      entry["shape_id"] = shapes[best].id;
      entry["measured_height_m"] = shapes[best].max_deviation_m;
      entry["height_error_m"] = shapes[best].max_deviation_m - o.height_m;
    }
    list.push_back(entry);
  }
  // A shape no object matched is false only on clean hull: one within an object's reach is a
  // second shape of that object (Algorithm 1's clusters of one object can stay apart).
  int false_shapes = 0, split_shapes = 0;
  for (size_t s = 0; s < shapes.size(); ++s) {
    if (shape_matched[s]) continue;
    const bool on_object = std::any_of(objects.begin(), objects.end(), [&](const TruthObject& o) {
      return (shapes[s].centroid_world - o.center).norm() <= o.radius_m + match_distance_m;
    });
    ++(on_object ? split_shapes : false_shapes);
  }
  return {{"objects", list},
          {"found", found},
          {"missed", int(objects.size()) - found},
          {"false_shapes", false_shapes},
          {"extra_shapes_on_objects", split_shapes},
          {"match_distance_m", match_distance_m},
          {"note", "object centres are in truth.yaml's world frame; shapes in the BA's"}};
}

}  // namespace

json truth_evaluation(const fs::path& truth_yaml, const std::vector<inspect::ShapeSummary>& shapes,
                      double match_distance_m) {
  return evaluate_objects(truth_objects(truth_yaml), shapes, match_distance_m);
}

}  // namespace keel::pipeline
