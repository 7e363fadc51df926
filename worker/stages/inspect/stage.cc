// Stage `inspect`, as numbered steps:
//   1. options (--set inspect.x=v), ba_solution.json of the `ba` stage and the CAD mesh (the
//      job's CAD blob, else the mission's cad_mesh), moved into the world frame by x_gM;
//   2. run_inspect (Algorithms 1-2 of seed 001);
//   3. artifacts: mesh_remeshed.drc / .ply with the per-vertex deviation, shapes.json;
//   4. report: shapes and heights; with truth.yaml, foreign objects found / missed.
#include "worker/stages/inspect/stage.h"
#include "worker/pipeline/report_html_parts.h"
#include "worker/pipeline/stage_options.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "proto/contract_error.h"
#include "worker/inspect/inspect.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/mesh/mesh_ply_writer.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/mission.h"
#include "worker/io/yaml_json.h"
#include "worker/stages/ba/artifacts.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/pipeline/report.h"

namespace keel::pipeline {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using proto::ContractError;

void local_require(bool ok, const std::string& option, const std::string& expected) {
  if (!ok) throw ContractError("options.inspect." + option + ": expected " + expected);
}

BaSolution read_solution(const fs::path& path) {
  std::ifstream in(path);
  if (!in)
    throw std::runtime_error("inspect needs " + path.filename().string() +
                             " of a `ba` stage: cannot open " + path.string());
  json document;
  try {
    document = json::parse(in);
  } catch (const json::parse_error& e) {
    throw std::runtime_error(path.string() + ": not valid JSON: " + e.what());
  }
  return ba_solution_from_json(document, path.filename().string());
}

TriangleMesh moved(TriangleMesh mesh, const Pose3& T_world_model) {
  for (auto& v : mesh.vertices) v = T_world_model * v;
  for (auto& n : mesh.vertex_normals) n = T_world_model.linear() * n;
  return mesh;
}

inspect::InspectInput build_input(const BaSolution& solution, TriangleMesh cad_in_world) {
  inspect::InspectInput input;
  input.cad_in_world = std::move(cad_in_world);
  input.T_world_camera = solution.T_world_camera;
  for (const auto& l : solution.landmarks)
    input.landmarks.push_back({l.point_world, l.h_m, l.lambda, l.views});
  return input;
}

// ---- step 4: foreign objects of truth.yaml ----------------------------------------------------

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

class InspectStage : public Stage {
 public:
  std::string name() const override { return "inspect"; }
  std::string report_html(const report_html::Ref& section,
                          const ReportHtmlInputs& inputs) const override {
    return report_html::inspect_section(section);
  }

  StageResult run(StageContext& context) override {
    const InspectStageOptions options = InspectStageOptions::from_json(context.options);
    const BaSolution solution = read_solution(context.work_dir / kBaSolutionFile);
    const io::Mission mission = io::load_mission(context.mission_dir);
    const fs::path cad = !context.cad_path.empty() ? context.cad_path : mission.cad_mesh_path;
    if (cad.empty())
      throw std::runtime_error(
          "inspect needs a CAD mesh: the job has none and mission.yaml has no cad_mesh");
    const inspect::InspectInput input =
        build_input(solution, moved(io::read_mesh(cad), solution.T_world_model));
    context.progress(0.1);
    context.check_canceled();

    const inspect::InspectResult result = inspect::run_inspect(input, options.inspect);
    context.progress(0.8);

    // Step 3: artifacts.
    const std::vector<io::ScalarField> fields = {
        {"deviation",
         std::vector<float>(result.vertex_deviation_m.begin(), result.vertex_deviation_m.end())}};
    io::DracoOptions draco;
    draco.position_bits = options.draco_position_bits;
    draco.field_bits = options.draco_field_bits;
    const io::DracoEncoded encoded = io::encode_draco_mesh(result.remeshed, fields, draco);
    io::write_draco_file(context.work_dir / kRemeshedDracoFile, encoded.bytes);
    StageResult out;
    out.artifacts.push_back(kRemeshedDracoFile);
    out.artifacts.push_back(
        write_draco_sidecar(context.work_dir, kRemeshedDracoFile, encoded.summary, "world"));
    if (options.write_ply) {
      io::write_ply_mesh(context.work_dir / kRemeshedPlyFile, result.remeshed, fields);
      out.artifacts.push_back(kRemeshedPlyFile);
    }
    write_json_atomically(
        context.work_dir / kShapesFile,
        nlohmann::ordered_json(inspect::shapes_to_json(result.shapes, options.inspect)));
    out.artifacts.push_back(kShapesFile);

    // Step 4: report.
    json& r = out.report;
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
    r["draco"] = {{"bytes", encoded.bytes.size()},
                  {"max_position_error_m", encoded.max_position_error_m},
                  {"position_error_bound_m", encoded.position_error_bound_m}};
    json shapes = json::array();
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
    if (!mission.ground_truth_path.empty()) {
      const auto objects = truth_objects(mission.ground_truth_path);
      r["truth"] = evaluate_objects(objects, result.shapes, options.match_distance_m);
    }
    context.progress(1.0);
    return out;
  }
};

}  // namespace

InspectStageOptions InspectStageOptions::from_json(const json& options) {
  InspectStageOptions o;
  if (options.is_null()) return o;
  StageOptionReader r(options, "inspect");
  auto& in = o.inspect;
  in.tau_m = r.optional<double>("tau_m", in.tau_m);
  in.tau_noise_sigmas = r.optional<double>("tau_noise_sigmas", in.tau_noise_sigmas);
  in.dbscan_eps_m = r.optional<double>("dbscan_eps_m", in.dbscan_eps_m);
  in.dbscan_min_pts = r.optional<int>("dbscan_min_pts", in.dbscan_min_pts);
  in.min_shape_views = r.optional<int>("min_shape_views", in.min_shape_views);
  in.alpha_m = r.optional<double>("alpha_m", in.alpha_m);
  in.view_range_m = r.optional<double>("view_range_m", in.view_range_m);
  in.max_behind_vertex_m = r.optional<double>("max_behind_vertex_m", in.max_behind_vertex_m);
  in.top_site_noise_sigmas = r.optional<double>("top_site_noise_sigmas", in.top_site_noise_sigmas);
  in.top_spacings = r.optional<int>("top_spacings", in.top_spacings);
  o.draco_position_bits = r.optional<int>("draco_position_bits", o.draco_position_bits);
  o.draco_field_bits = r.optional<int>("draco_field_bits", o.draco_field_bits);
  o.write_ply = r.optional<bool>("write_ply", o.write_ply);
  o.match_distance_m = r.optional<double>("match_distance_m", o.match_distance_m);
  r.finish();
  try {
    inspect::validate(o.inspect);
  } catch (const std::invalid_argument& e) {
    throw ContractError(std::string("options.inspect: ") + e.what());
  }
  local_require(o.draco_position_bits >= 1 && o.draco_position_bits <= 30, "draco_position_bits",
          "an integer in [1, 30]");
  local_require(o.draco_field_bits >= 0 && o.draco_field_bits <= 30, "draco_field_bits",
          "an integer in [0, 30]");
  local_require(std::isfinite(o.match_distance_m) && o.match_distance_m >= 0, "match_distance_m",
          "a number >= 0");
  return o;
}

std::unique_ptr<Stage> make_inspect_stage() { return std::make_unique<InspectStage>(); }

}  // namespace keel::pipeline
