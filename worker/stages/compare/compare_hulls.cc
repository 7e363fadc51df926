#include "worker/stages/compare/compare_hulls.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

#include "core/robust_spread.h"
#include "worker/compare/nearest_index.h"
#include "worker/compare/shape_matching.h"
#include "worker/io/draco/draco_codec.h"
#include "worker/io/mesh/mesh_ply_writer.h"
#include "worker/mapping/map_metrics.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/stages/compare/artifacts.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;

json vector_json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

json pose_difference(const Pose3& T) {
  return {{"translation_m", vector_json(T.translation())},
          {"translation_norm_m", T.translation().norm()},
          {"rotation_deg", Eigen::AngleAxisd(T.linear()).angle() * 180.0 / M_PI}};
}

// Per vertex of B: its deviation minus that of A's nearest vertex (both from the same CAD mesh;
// Draco reorders vertices, so they are paired by position in the model frame).
struct VertexChange {
  std::vector<float> deviation_a, change;
  std::vector<double> pairing_m;    // each vertex's distance to its pair
  std::vector<float> moved_change;  // the change where either survey's deviation is not 0
};

VertexChange vertex_change(const HullSurvey& a, const HullSurvey& b) {
  std::vector<Eigen::Vector3f> a_vertices;
  for (const auto& v : a.mesh.mesh.vertices) a_vertices.push_back(v.cast<float>());
  const compare::NearestIndex index(a_vertices);
  const size_t n = b.mesh.mesh.vertices.size();
  VertexChange out;
  out.deviation_a.resize(n);
  out.change.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const compare::Neighbour nb = index.nearest(b.mesh.mesh.vertices[i].cast<float>());
    out.deviation_a[i] = a.deviation[nb.index];
    out.change[i] = b.deviation[i] - out.deviation_a[i];
    out.pairing_m.push_back(nb.distance_m);
    if (b.deviation[i] != 0.0f || out.deviation_a[i] != 0.0f)
      out.moved_change.push_back(out.change[i]);
  }
  return out;
}

// change_hull.drc (+ its sidecar) and change_hull.ply: B's mesh with both deviations and their
// change. Returns the Draco file's size.
size_t write_change_mesh(const StageContext& context, const CompareStageOptions& options,
                         const HullSurvey& b, const VertexChange& v,
                         std::vector<std::string>* artifacts) {
  const std::vector<io::ScalarField> fields = {
      {"deviation_a", v.deviation_a}, {"deviation_b", b.deviation}, {"deviation_change", v.change}};
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
  return encoded.bytes.size();
}

// changes.json's `shapes` rows: kept (with growth), new, gone, in match order.
json shape_rows(const compare::ShapeChanges& c, const std::vector<compare::SurveyShape>& b) {
  json table = json::array();
  for (const compare::ShapeChange& change : c.changes) {
    const compare::ShapeMatch& m = change.match;
    if (m.a >= 0 && m.b >= 0) {
      const compare::SurveyShape &sa = c.a_moved[m.a], &sb = b[m.b];
      const compare::ShapeGrowth& g = change.growth;
      table.push_back({{"status", "kept"},
                       {"shape_a", sa.id},
                       {"shape_b", sb.id},
                       {"centroid_model_m", vector_json(sb.centroid_model)},
                       {"centroid_shift_m", m.distance_m},
                       {"height_a_m", sa.height_m},
                       {"height_b_m", sb.height_m},
                       {"height_growth_m", g.height_m},
                       {"height_growth_sigma_m", g.height_sigma_m},
                       {"footprint_a_m2", g.footprint_a_m2},
                       {"footprint_b_m2", g.footprint_b_m2},
                       {"footprint_growth_m2", g.footprint_b_m2 - g.footprint_a_m2},
                       {"footprint_growth_sigma_m2", g.footprint_sigma_m2},
                       {"significant_growth", g.significant}});
    } else if (m.b >= 0) {
      const compare::SurveyShape& sb = b[m.b];
      table.push_back({{"status", "new"},
                       {"shape_b", sb.id},
                       {"centroid_model_m", vector_json(sb.centroid_model)},
                       {"height_b_m", sb.height_m},
                       {"footprint_b_m2", compare::footprint_m2(sb)}});
    } else {
      const compare::SurveyShape& sa = c.a_moved[m.a];
      table.push_back({{"status", "gone"},
                       {"shape_a", sa.id},
                       {"centroid_model_m", vector_json(sa.centroid_model)},
                       {"height_a_m", sa.height_m},
                       {"footprint_a_m2", compare::footprint_m2(sa)}});
    }
  }
  return table;
}

}  // namespace

json compare_hulls(StageContext& context, const CompareStageOptions& options,
                   std::vector<std::string>* artifacts) {
  const HullSurvey a = load_hull_survey(context.input_jobs.at(0), "A");
  const HullSurvey b = load_hull_survey(context.input_jobs.at(1), "B");
  context.progress(0.3);
  context.check_canceled();

  const VertexChange vertices = vertex_change(a, b);
  const size_t draco_bytes = write_change_mesh(context, options, b, vertices, artifacts);
  context.progress(0.7);

  const compare::ShapeChanges shapes = compare::compare_shapes(
      a.shapes, b.shapes, a.sigmas, b.sigmas, options.shape_max_offset_m, options.growth_sigmas);
  const std::vector<double>& pairing = vertices.pairing_m;
  return {{"frame", "model"},
          {"x_gM_a", pose_difference(a.T_world_model)},
          {"x_gM_b", pose_difference(b.T_world_model)},
          // Meaningful when both surveys share a world frame (keel-sim's do).
          {"x_gM_difference", pose_difference(a.T_world_model.inverse() * b.T_world_model)},
          {"vertices", b.mesh.mesh.vertices.size()},
          {"vertex_pairing_median_m", robust_spread(pairing).median},
          {"vertex_pairing_max_m",
           pairing.empty() ? 0.0 : *std::max_element(pairing.begin(), pairing.end())},
          {"deviation_change_m",
           mapping::to_json(mapping::summarize(vertices.moved_change, options.histogram_bins))},
          {"shapes_a", a.shapes.size()},
          {"shapes_b", b.shapes.size()},
          {"kept", shapes.kept},
          {"new", shapes.added},
          {"gone", shapes.gone},
          {"significantly_grown", shapes.grown},
          {"shape_registration",
           {{"translation_m", vector_json(shapes.registration.translation_model)},
            {"translation_norm_m", shapes.registration.translation_model.norm()},
            {"pairs", shapes.registration.pairs},
            {"note",
             "A's shapes moved by this translation (model frame) before matching: the offset most "
             "persisting shapes agree on, each survey's x_gM being loose along the hull; zero "
             "with fewer than two agreeing shapes. A's centroids in `shapes` are moved"}}},
          {"height_sigma_a_m", a.sigmas.height_m},
          {"height_sigma_b_m", b.sigmas.height_m},
          {"footprint_note",
           "footprint = pi r^2 with r a quarter of the two largest extents of the shape's world "
           "bounding box; r's uncertainty is half of DBSCAN's eps"},
          {"shapes", shape_rows(shapes, b.shapes)},
          {"draco", {{"file", change_draco_file(kHullChangeName)}, {"bytes", draco_bytes}}}};
}

}  // namespace keel::pipeline
