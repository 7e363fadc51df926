#include "worker/stages/ingest/mission_report.h"

#include <stdexcept>

#include "worker/io/display_path.h"
#include "worker/io/mesh/mesh_check.h"
#include "worker/io/mesh/mesh_reader.h"

namespace keel::pipeline {

// A mesh that cannot serve as a CAD prior fails here, naming the problem (read_mesh refuses
// non-finite vertices and meshes without faces, naming the file and line); what it can
// serve with goes into the report and the warnings.
nlohmann::json cad_report(const std::filesystem::path& path, nlohmann::json& warnings) {
  const TriangleMesh mesh = io::read_mesh(path);
  const io::MeshCheckReport check = io::check_mesh(mesh);
  if (check.degenerate_faces() == check.num_faces)
    throw std::runtime_error(io::display_path(path) + ": all " + std::to_string(check.num_faces) +
                             " triangles are degenerate (no surface to align to)");
  nlohmann::json r = check.to_json();
  r["file"] = path.filename().string();
  for (const auto& w : check.warnings) warnings.push_back("cad: " + w.message);
  return r;
}

}  // namespace keel::pipeline
