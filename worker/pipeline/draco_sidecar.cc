#include "worker/pipeline/draco_sidecar.h"

#include "worker/pipeline/report.h"

namespace keel::pipeline {

namespace {

nlohmann::ordered_json vector_json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

std::string sidecar_file(const std::string& draco_file) {
  return std::filesystem::path(draco_file).replace_extension(".json").string();
}

nlohmann::ordered_json draco_sidecar_json(const std::string& draco_file,
                                          const io::DracoSummary& summary, const std::string& frame,
                                          const nlohmann::json& preview) {
  nlohmann::ordered_json out;
  out["file"] = draco_file;
  out["kind"] = summary.kind;
  out["frame"] = frame;
  out["points"] = summary.points;
  out["faces"] = summary.faces;
  out["bbox_min"] = vector_json(summary.bbox_min);
  out["bbox_max"] = vector_json(summary.bbox_max);
  out["position_unique_id"] = summary.position_unique_id;
  out["attributes"] = nlohmann::ordered_json::object();
  for (const auto& a : summary.attributes) {
    nlohmann::ordered_json attribute = {{"unique_id", a.unique_id},
                                        {"data_type", a.data_type},
                                        {"components", a.components},
                                        {"min", a.min},
                                        {"max", a.max}};
    if (!a.labels.empty()) attribute["labels"] = a.labels;
    if (a.no_data) attribute["no_data"] = *a.no_data;
    out["attributes"][a.name] = attribute;
  }
  if (!preview.is_null()) out["preview"] = preview;
  return out;
}

std::string write_draco_sidecar(const std::filesystem::path& work_dir,
                                const std::string& draco_file, const io::DracoSummary& summary,
                                const std::string& frame, const nlohmann::json& preview) {
  const std::string name = sidecar_file(draco_file);
  write_json_atomically(work_dir / name, draco_sidecar_json(draco_file, summary, frame, preview));
  return name;
}

}  // namespace keel::pipeline
