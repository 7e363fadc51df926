#include "worker/stages/inspect/outputs.h"

#include "worker/io/draco/draco_codec.h"
#include "worker/io/mesh/mesh_ply_writer.h"
#include "worker/pipeline/draco_sidecar.h"
#include "worker/pipeline/report.h"
#include "worker/stages/inspect/artifacts.h"

namespace keel::pipeline {

InspectArtifacts write_inspect_artifacts(const std::filesystem::path& work_dir,
                                         const inspect::InspectResult& result,
                                         const InspectStageOptions& options) {
  const std::vector<io::ScalarField> fields = {
      {"deviation",
       std::vector<float>(result.vertex_deviation_m.begin(), result.vertex_deviation_m.end())}};
  io::DracoOptions draco;
  draco.position_bits = options.draco_position_bits;
  draco.field_bits = options.draco_field_bits;
  const io::DracoEncoded encoded = io::encode_draco_mesh(result.remeshed, fields, draco);
  io::write_draco_file(work_dir / kRemeshedDracoFile, encoded.bytes);
  InspectArtifacts out;
  out.files.push_back(kRemeshedDracoFile);
  out.files.push_back(write_draco_sidecar(work_dir, kRemeshedDracoFile, encoded.summary, "world"));
  if (options.write_ply) {
    io::write_ply_mesh(work_dir / kRemeshedPlyFile, result.remeshed, fields);
    out.files.push_back(kRemeshedPlyFile);
  }
  write_json_atomically(work_dir / kShapesFile, nlohmann::ordered_json(inspect::shapes_to_json(
                                                    result.shapes, options.inspect)));
  out.files.push_back(kShapesFile);
  out.draco = {{"bytes", encoded.bytes.size()},
               {"max_position_error_m", encoded.max_position_error_m},
               {"position_error_bound_m", encoded.position_error_bound_m}};
  return out;
}

}  // namespace keel::pipeline
