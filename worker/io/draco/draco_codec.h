// Draco compression of Keel's maps (point clouds) and remeshed hulls (meshes), with the
// position error the quantization introduced measured by decoding the result.
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "core/triangle_mesh.h"
#include "worker/io/draco/draco_header_check.h"
#include "worker/io/draco/draco_summary.h"
#include "worker/io/mesh/mesh_scalar_field.h"

namespace keel::io {

struct DracoOptions {
  int position_bits = 14;     // quantization of positions, 1..30 (Draco's own default is 11)
  int field_bits = 12;        // quantization of scalar fields, 1..30; 0 stores them lossless
  int compression_level = 7;  // 0 (fastest) .. 10 (smallest); Draco speed = 10 - level
};

struct DracoEncoded {
  std::string bytes;  // a complete .drc file
  // Largest |decoded - original| over all points (vertices used by faces), measured by
  // decoding `bytes`.
  double max_position_error_m = 0.0;
  // Draco quantizes positions on a cube of this side (largest bounding-box extent), in
  // 2^bits - 1 steps, so each coordinate is off by at most half a step.
  double position_range_m = 0.0;
  double position_error_bound_m = 0.0;  // sqrt(3)/2 * range / (2^bits - 1)
  // How max_position_error_m was measured: "replica" (point clouds: each point's decoded
  // position predicted with Draco's quantizer arithmetic, accepted only when the predicted
  // positions equal the decoded ones as a multiset; O(n) time and no extra memory) or
  // "nearest_decoded" (meshes, or a replica mismatch: the nearest decoded point to each input
  // point, found on a hash grid).
  std::string error_method;
  // What the file holds, from the same decoding (counts, box, attribute ids and value ranges).
  DracoSummary summary;
};

// Attributes of a cloud given as parts, beyond intensity.
struct PartsAttributes {
  // A label attribute (GENERIC, uint8, stored losslessly) when label_name is not empty: every
  // point of parts[k] holds k, and part_labels (one per part, at most 256) are stored as the
  // attribute's metadata entry kDracoLabelsEntry (a JSON array). A combined map's `sensor`.
  std::string label_name;
  std::vector<std::string> part_labels;
  // Float fields over the concatenated parts (one value per point, in part order), quantized
  // like every scalar field (DracoOptions::field_bits).
  std::vector<ScalarField> fields;
  // Empty, or per field a value meaning "undefined here" (NaN: the field has none), stored as
  // the field's metadata entry kDracoNoDataEntry. Keep it below every defined value:
  // quantization returns the attribute's minimum exactly.
  std::vector<float> fields_no_data;
};

// Positions plus per-point scalar fields (stored as generic attributes named by metadata
// entry "name", as draco_transcoder and Keel's decoder read them). Throws
// std::invalid_argument for an empty cloud, non-finite positions, bad options or fields,
// std::runtime_error when Draco fails.
DracoEncoded encode_draco_point_cloud(const std::vector<Eigen::Vector3f>& positions,
                                      const std::vector<ScalarField>& fields = {},
                                      const DracoOptions& options = {});
// As above; a cloud's intensity becomes the field "intensity".
DracoEncoded encode_draco_point_cloud(const PointCloud& cloud,
                                      const std::vector<ScalarField>& fields = {},
                                      const DracoOptions& options = {});

// The concatenation of `parts` (a combined map's sensor maps, Eq. (21)) without building it:
// the same bytes and figures as encoding the concatenated cloud. Intensity is stored when every
// non-empty part has it (as mapping::append_points merges clouds). Throws as above.
DracoEncoded encode_draco_point_cloud(const std::vector<const PointCloud*>& parts,
                                      const DracoOptions& options = {},
                                      const PartsAttributes& attributes = {});
// The same in two steps, to run on different threads: the encoding (`bytes` only), then the
// round trip that fills the other fields (throwing as the encoder does). `parts` and `options`
// must be the same in both.
DracoEncoded encode_draco_point_cloud_bytes(const std::vector<const PointCloud*>& parts,
                                            const DracoOptions& options = {},
                                            const PartsAttributes& attributes = {});
void measure_draco_point_cloud(const std::vector<const PointCloud*>& parts,
                               const DracoOptions& options, DracoEncoded* encoded);

// Positions, faces (edgebreaker) and per-vertex scalar fields such as `deviation`. Vertices
// that no face uses are not stored (Draco drops them).
DracoEncoded encode_draco_mesh(const TriangleMesh& mesh,
                               const std::vector<ScalarField>& vertex_fields = {},
                               const DracoOptions& options = {});

struct DracoPointCloud {
  std::vector<Eigen::Vector3f> positions;
  std::vector<ScalarField> fields;  // generic 1-component attributes, by metadata name
};
struct DracoMesh {
  TriangleMesh mesh;
  std::vector<ScalarField> fields;
};

// Throw std::runtime_error naming `what` (a file name, say) when the bytes do not decode, when
// their header declares more than `limits` (draco_header_check.h), or when Draco cannot get the
// memory the file asks for.
DracoPointCloud decode_draco_point_cloud(const std::string& bytes,
                                         const std::string& what = "draco buffer",
                                         const DracoLimits& limits = {});
DracoMesh decode_draco_mesh(const std::string& bytes, const std::string& what = "draco buffer",
                            const DracoLimits& limits = {});

// Writes bytes to a temporary sibling, then renames it into place; throws naming the file.
void write_draco_file(const std::filesystem::path& path, const std::string& bytes);
std::string read_draco_file(const std::filesystem::path& path);

}  // namespace keel::io
