#include "worker/stages/compare/compare_hulls.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "worker/compare/nearest_index.h"
#include "core/robust_spread.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/mesh/mesh_ply_writer.h"
#include "worker/mapping/map_metrics.h"
#include "worker/stages/ba/artifacts.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/stages/inspect/artifacts.h"
#include "worker/pipeline/report.h"

namespace keel::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json read_json(const fs::path& path, const std::string& job) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("job " + job + ": no " + path.filename().string());
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    throw std::runtime_error("job " + job + ": " + path.filename().string() +
                             ": not valid JSON: " + e.what());
  }
}

json vector_json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// One survey's hull products in the model frame.
struct Survey {
  std::string job;
  Pose3 T_world_model = Pose3::Identity();
  io::DracoMesh mesh;  // vertices moved into the model frame
  std::vector<float> deviation;
  std::vector<SurveyShape> shapes;
  double height_sigma_m = 0.0;  // inspect's deviation noise sigma
  double radius_sigma_m = 0.0;  // half of DBSCAN's eps
};

Eigen::Vector3d json_vector(const json& v, const std::string& what) {
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    throw std::runtime_error(what + ": expected 3 numbers");
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

Survey load_survey(const InputJob& input, const std::string& fallback_id) {
  Survey s;
  s.job = input.job.value("id", fallback_id);
  const BaSolution solution =
      ba_solution_from_json(read_json(input.dir / kBaSolutionFile, s.job), kBaSolutionFile);
  s.T_world_model = solution.T_world_model;
  const Pose3 T_model_world = s.T_world_model.inverse();
  try {
    s.mesh = io::decode_draco_mesh(io::read_draco_file(input.dir / kRemeshedDracoFile),
                                   kRemeshedDracoFile);
  } catch (const std::exception& e) {
    throw std::runtime_error("job " + s.job + ": " + e.what());
  }
  for (auto& v : s.mesh.mesh.vertices) v = T_model_world * v;
  for (const auto& f : s.mesh.fields)
    if (f.name == "deviation") s.deviation = f.values;
  if (s.deviation.size() != s.mesh.mesh.vertices.size())
    throw std::runtime_error("job " + s.job + ": " + kRemeshedDracoFile +
                             " has no per-vertex `deviation`");

  const json shapes = read_json(input.dir / kShapesFile, s.job);
  const std::string where = "job " + s.job + ": " + kShapesFile;
  if (!shapes.contains("shapes") || !shapes["shapes"].is_array())
    throw std::runtime_error(where + ": expected a `shapes` list");
  const double eps =
      shapes.contains("options") ? shapes["options"].value("dbscan_eps_m", 0.0) : 0.0;
  s.radius_sigma_m = 0.5 * eps;
  for (size_t i = 0; i < shapes["shapes"].size(); ++i) {
    const json& j = shapes["shapes"][i];
    const std::string at = where + ": shapes[" + std::to_string(i) + "]";
    SurveyShape shape;
    shape.id = j.value("id", int(i));
    shape.centroid_model =
        T_model_world * json_vector(j.at("centroid_world_m"), at + ".centroid_world_m");
    shape.height_m = j.value("max_deviation_m", 0.0);
    shape.height_sampling_sigma_m = j.value("height_sampling_sigma_m", 0.0);
    // The footprint from the world bounding box: a disc of radius R tilted anywhere spans
    // 2R sqrt(1 - n_i^2) along axis i, so the two largest spans average 1.6R-2R.
    Eigen::Vector3d extent = json_vector(j.at("extent_m"), at + ".extent_m");
    std::sort(extent.data(), extent.data() + 3);
    shape.radius_m = 0.25 * (extent[1] + extent[2]);
    s.shapes.push_back(shape);
  }
  const json report = read_json(input.dir / kReportFileName, s.job);
  if (report.contains("stages") && report["stages"].contains("inspect"))
    s.height_sigma_m = report["stages"]["inspect"].value("deviation_noise_sigma_m", 0.0);
  return s;
}

json pose_difference(const Pose3& T) {
  return {{"translation_m", vector_json(T.translation())},
          {"translation_norm_m", T.translation().norm()},
          {"rotation_deg", Eigen::AngleAxisd(T.linear()).angle() * 180.0 / M_PI}};
}

}  // namespace

bool has_hull_products(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / kRemeshedDracoFile, ec) &&
         fs::is_regular_file(dir / kShapesFile, ec) &&
         fs::is_regular_file(dir / kBaSolutionFile, ec);
}

std::vector<ShapeMatch> match_shapes(const std::vector<SurveyShape>& a,
                                     const std::vector<SurveyShape>& b) {
  std::vector<ShapeMatch> candidates;
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j) {
      const double d = (a[i].centroid_model - b[j].centroid_model).norm();
      if (d < a[i].radius_m + b[j].radius_m) candidates.push_back({int(i), int(j), d});
    }
  std::sort(candidates.begin(), candidates.end(),
            [](const ShapeMatch& x, const ShapeMatch& y) { return x.distance_m < y.distance_m; });
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<ShapeMatch> out;
  for (const ShapeMatch& m : candidates) {
    if (used_a[m.a] || used_b[m.b]) continue;
    used_a[m.a] = used_b[m.b] = true;
    out.push_back(m);
  }
  for (size_t i = 0; i < a.size(); ++i)
    if (!used_a[i]) out.push_back({int(i), -1, 0.0});
  for (size_t j = 0; j < b.size(); ++j)
    if (!used_b[j]) out.push_back({-1, int(j), 0.0});
  return out;
}

namespace {

// A's shapes moved by `t`.
std::vector<SurveyShape> shifted(std::vector<SurveyShape> shapes, const Eigen::Vector3d& t) {
  for (SurveyShape& shape : shapes) shape.centroid_model += t;
  return shapes;
}

}  // namespace

ShapeRegistration register_shapes(const std::vector<SurveyShape>& a,
                                  const std::vector<SurveyShape>& b, double max_offset_m,
                                  int min_pairs) {
  ShapeRegistration best;
  double best_norm = 0.0;
  for (const SurveyShape& sa : a)
    for (const SurveyShape& sb : b) {
      const Eigen::Vector3d candidate = sb.centroid_model - sa.centroid_model;
      if (candidate.norm() > max_offset_m) continue;
      std::vector<ShapeMatch> agreeing;
      for (const ShapeMatch& m : match_shapes(shifted(a, candidate), b))
        if (m.a >= 0 && m.b >= 0) agreeing.push_back(m);
      const int pairs = static_cast<int>(agreeing.size());
      // The most pairs; among equals the smaller offset (no evidence for moving further).
      if (pairs < best.pairs || (pairs == best.pairs && candidate.norm() >= best_norm)) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const ShapeMatch& m : agreeing) mean += b[m.b].centroid_model - a[m.a].centroid_model;
      best.pairs = pairs;
      best.translation_model = mean / pairs;
      best_norm = candidate.norm();
    }
  if (best.pairs < min_pairs || best.translation_model.norm() > max_offset_m) return {};
  return best;
}

json compare_hulls(StageContext& context, const CompareStageOptions& options,
                   std::vector<std::string>* artifacts) {
  const Survey a = load_survey(context.input_jobs.at(0), "A");
  const Survey b = load_survey(context.input_jobs.at(1), "B");
  context.progress(0.3);
  context.check_canceled();

  // Per vertex: B's deviation minus that of A's nearest vertex (both from the same CAD mesh;
  // Draco reorders vertices, so they are paired by position in the model frame).
  std::vector<Eigen::Vector3f> a_vertices;
  for (const auto& v : a.mesh.mesh.vertices) a_vertices.push_back(v.cast<float>());
  const compare::NearestIndex index(a_vertices);
  const size_t n = b.mesh.mesh.vertices.size();
  std::vector<float> deviation_a(n), change(n);
  std::vector<double> pairing;
  std::vector<float> moved_change;
  for (size_t i = 0; i < n; ++i) {
    const compare::Neighbour nb = index.nearest(b.mesh.mesh.vertices[i].cast<float>());
    deviation_a[i] = a.deviation[nb.index];
    change[i] = b.deviation[i] - deviation_a[i];
    pairing.push_back(nb.distance_m);
    if (b.deviation[i] != 0.0f || deviation_a[i] != 0.0f) moved_change.push_back(change[i]);
  }
  const std::vector<io::ScalarField> fields = {
      {"deviation_a", deviation_a}, {"deviation_b", b.deviation}, {"deviation_change", change}};
  io::DracoOptions draco;
  draco.position_bits = std::min(options.draco_position_bits, 16);
  draco.field_bits = options.draco_field_bits;
  draco.compression_level = options.draco_compression_level;
  const io::DracoEncoded encoded = io::encode_draco_mesh(b.mesh.mesh, fields, draco);
  io::write_draco_file(context.work_dir / change_draco_file(kHullChangeName), encoded.bytes);
  artifacts->push_back(change_draco_file(kHullChangeName));
  artifacts->push_back(write_draco_sidecar(context.work_dir, change_draco_file(kHullChangeName),
                                           encoded.summary, "model"));
  if (options.write_ply) {
    io::write_ply_mesh(context.work_dir / change_ply_file(kHullChangeName), b.mesh.mesh, fields);
    artifacts->push_back(change_ply_file(kHullChangeName));
  }
  context.progress(0.7);

  // Shapes. A height's error: inspect's deviation noise, and how far the shape's top may lie
  // beyond its highest feature (shapes.json's height_sampling_sigma_m), independent between
  // the surveys.
  const double noise_sigma = std::hypot(a.height_sigma_m, b.height_sigma_m);
  json table = json::array();
  int kept = 0, added = 0, gone = 0, grown = 0;
  const ShapeRegistration registration =
      register_shapes(a.shapes, b.shapes, options.shape_max_offset_m);
  const std::vector<SurveyShape> a_shapes = shifted(a.shapes, registration.translation_model);
  for (const ShapeMatch& m : match_shapes(a_shapes, b.shapes)) {
    json row;
    if (m.a >= 0 && m.b >= 0) {
      const SurveyShape &sa = a_shapes[m.a], &sb = b.shapes[m.b];
      const double area_a = M_PI * sa.radius_m * sa.radius_m,
                   area_b = M_PI * sb.radius_m * sb.radius_m;
      // d(pi r^2) = 2 pi r dr, the two surveys' radius errors independent.
      const double area_sigma = std::hypot(2 * M_PI * sa.radius_m * a.radius_sigma_m,
                                           2 * M_PI * sb.radius_m * b.radius_sigma_m);
      const double growth = sb.height_m - sa.height_m;
      const double height_sigma = std::hypot(
          noise_sigma, std::hypot(sa.height_sampling_sigma_m, sb.height_sampling_sigma_m));
      const bool significant = std::abs(growth) > options.growth_sigmas * height_sigma;
      row = {{"status", "kept"},
             {"shape_a", sa.id},
             {"shape_b", sb.id},
             {"centroid_model_m", vector_json(sb.centroid_model)},
             {"centroid_shift_m", m.distance_m},
             {"height_a_m", sa.height_m},
             {"height_b_m", sb.height_m},
             {"height_growth_m", growth},
             {"height_growth_sigma_m", height_sigma},
             {"footprint_a_m2", area_a},
             {"footprint_b_m2", area_b},
             {"footprint_growth_m2", area_b - area_a},
             {"footprint_growth_sigma_m2", area_sigma},
             {"significant_growth", significant}};
      ++kept;
      grown += significant && growth > 0;
    } else if (m.b >= 0) {
      const SurveyShape& sb = b.shapes[m.b];
      row = {{"status", "new"},
             {"shape_b", sb.id},
             {"centroid_model_m", vector_json(sb.centroid_model)},
             {"height_b_m", sb.height_m},
             {"footprint_b_m2", M_PI * sb.radius_m * sb.radius_m}};
      ++added;
    } else {
      const SurveyShape& sa = a_shapes[m.a];
      row = {{"status", "gone"},
             {"shape_a", sa.id},
             {"centroid_model_m", vector_json(sa.centroid_model)},
             {"height_a_m", sa.height_m},
             {"footprint_a_m2", M_PI * sa.radius_m * sa.radius_m}};
      ++gone;
    }
    table.push_back(row);
  }
  const RobustSpread pairing_spread = robust_spread(pairing);
  json report = {
      {"frame", "model"},
      {"x_gM_a", pose_difference(a.T_world_model)},
      {"x_gM_b", pose_difference(b.T_world_model)},
      // Meaningful when both surveys share a world frame (keel-sim's do).
      {"x_gM_difference", pose_difference(a.T_world_model.inverse() * b.T_world_model)},
      {"vertices", n},
      {"vertex_pairing_median_m", pairing_spread.median},
      {"vertex_pairing_max_m",
       pairing.empty() ? 0.0 : *std::max_element(pairing.begin(), pairing.end())},
      {"deviation_change_m",
       mapping::to_json(mapping::summarize(moved_change, options.histogram_bins))},
      {"shapes_a", a.shapes.size()},
      {"shapes_b", b.shapes.size()},
      {"kept", kept},
      {"new", added},
      {"gone", gone},
      {"significantly_grown", grown},
      {"shape_registration",
       {{"translation_m", vector_json(registration.translation_model)},
        {"translation_norm_m", registration.translation_model.norm()},
        {"pairs", registration.pairs},
        {"note",
         "A's shapes moved by this translation (model frame) before matching: the offset most "
         "persisting shapes agree on, each survey's x_gM being loose along the hull; zero "
         "with fewer than two agreeing shapes. A's centroids in `shapes` are moved"}}},
      {"height_sigma_a_m", a.height_sigma_m},
      {"height_sigma_b_m", b.height_sigma_m},
      {"footprint_note",
       "footprint = pi r^2 with r a quarter of the two largest extents of the shape's world "
       "bounding box; r's uncertainty is half of DBSCAN's eps"},
      {"shapes", table},
      {"draco", {{"file", change_draco_file(kHullChangeName)}, {"bytes", encoded.bytes.size()}}}};
  return report;
}

}  // namespace keel::pipeline
