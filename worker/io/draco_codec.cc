#include "worker/io/draco_codec.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#include <draco/metadata/geometry_metadata.h>
#include <draco/point_cloud/point_cloud.h>
#include <draco/point_cloud/point_cloud_builder.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <unordered_map>

namespace keel::io {
namespace {

constexpr const char* kNameEntry = "name";  // attribute metadata key for a field's name

void check_options(const DracoOptions& options) {
  if (options.position_bits < 1 || options.position_bits > 30) {
    throw std::invalid_argument("DracoOptions.position_bits = " +
                                std::to_string(options.position_bits) + ": expected 1..30");
  }
  if (options.field_bits < 0 || options.field_bits > 30) {
    throw std::invalid_argument("DracoOptions.field_bits = " + std::to_string(options.field_bits) +
                                ": expected 0 (lossless) or 1..30");
  }
  if (options.compression_level < 0 || options.compression_level > 10) {
    throw std::invalid_argument("DracoOptions.compression_level = " +
                                std::to_string(options.compression_level) + ": expected 0..10");
  }
}

template <typename Vector>
void check_positions(const std::vector<Vector>& positions, const char* what) {
  if (positions.empty()) throw std::invalid_argument(std::string(what) + ": no points to encode");
  for (size_t i = 0; i < positions.size(); ++i) {
    if (!positions[i].allFinite()) {
      throw std::invalid_argument(std::string(what) + ": position " + std::to_string(i) +
                                  " is not finite (NaN or inf)");
    }
  }
}

draco::Encoder make_encoder(const DracoOptions& options) {
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, options.position_bits);
  if (options.field_bits > 0) {
    encoder.SetAttributeQuantization(draco::GeometryAttribute::GENERIC, options.field_bits);
  }
  const int speed = 10 - options.compression_level;
  encoder.SetSpeedOptions(speed, speed);
  return encoder;
}

void name_attribute(draco::PointCloud* geometry, int attribute_id, const std::string& name) {
  auto metadata = std::make_unique<draco::AttributeMetadata>();
  metadata->AddEntryString(kNameEntry, name);
  geometry->AddAttributeMetadata(attribute_id, std::move(metadata));
}

// Draco quantizes positions on a cube of side `range` = the largest extent of the float
// positions (as AttributeQuantizationTransform computes it), in 2^bits - 1 steps.
template <typename Vector>
double quantization_range(const std::vector<Vector>& positions) {
  Eigen::Vector3f lo = positions[0].template cast<float>();
  Eigen::Vector3f hi = lo;
  for (const auto& p : positions) {
    lo = lo.cwiseMin(p.template cast<float>());
    hi = hi.cwiseMax(p.template cast<float>());
  }
  const float range = (hi - lo).maxCoeff();
  return range > 0.f ? range : 1.0;  // Draco uses 1 for a single point
}

// Largest distance from each original point to the decoded point it became. Quantization
// rounds each coordinate to the nearest grid value, so a point's own decoded point is the
// nearest of all decoded points (they all sit on that grid): the nearest-neighbour distance
// is exactly the per-point error, with no need for Draco's (reordered) point ids. A hash
// grid of cell `step` finds it among the 27 cells around the original.
template <typename Vector>
double max_nearest_distance(const std::vector<Vector>& originals, const std::vector<bool>* used,
                            const std::vector<Eigen::Vector3f>& decoded, double step,
                            double tolerance) {
  struct CellHash {
    size_t operator()(const Eigen::Vector3i& c) const {
      return (static_cast<size_t>(c.x()) * 73856093u) ^ (static_cast<size_t>(c.y()) * 19349663u) ^
             (static_cast<size_t>(c.z()) * 83492791u);
    }
  };
  struct CellEqual {
    bool operator()(const Eigen::Vector3i& a, const Eigen::Vector3i& b) const { return a == b; }
  };
  Eigen::Vector3d origin = decoded[0].cast<double>();
  for (const auto& p : decoded) origin = origin.cwiseMin(p.cast<double>());
  // Cells centred on the grid nodes (round, not floor): a decoded point is alone in its cell,
  // and an original's own node is in the cell it rounds to, so one lookup usually suffices.
  auto cell_of = [&](const Eigen::Vector3d& p) -> Eigen::Vector3i {
    return ((p - origin) / step).array().round().cast<int>();
  };
  std::unordered_map<Eigen::Vector3i, std::vector<Eigen::Vector3d>, CellHash, CellEqual> grid;
  for (const auto& p : decoded) {
    auto& bucket = grid[cell_of(p.cast<double>())];
    // Duplicates of one grid point add nothing to a nearest-point search.
    if (std::find(bucket.begin(), bucket.end(), p.cast<double>()) == bucket.end()) {
      bucket.push_back(p.cast<double>());
    }
  }
  double max_error = 0.0;
  for (size_t i = 0; i < originals.size(); ++i) {
    if (used != nullptr && !(*used)[i]) continue;
    const Eigen::Vector3d p = originals[i].template cast<double>();
    const Eigen::Vector3i cell = cell_of(p);
    double best = std::numeric_limits<double>::infinity();
    if (const auto own = grid.find(cell); own != grid.end()) {
      for (const auto& q : own->second) best = std::min(best, (q - p).norm());
    }
    for (int dx = -1; dx <= 1 && !(best <= tolerance); ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(cell + Eigen::Vector3i(dx, dy, dz));
          if (it == grid.end()) continue;
          for (const auto& q : it->second) best = std::min(best, (q - p).norm());
        }
      }
    }
    if (best > tolerance) {
      throw std::runtime_error("draco round trip: point " + std::to_string(i) +
                               " has no decoded point within the quantization bound");
    }
    max_error = std::max(max_error, best);
  }
  return max_error;
}

template <typename Vector>
double error_tolerance(const std::vector<Vector>& originals, const DracoOptions& options,
                       DracoEncoded* result) {
  result->position_range_m = quantization_range(originals);
  const double step = result->position_range_m / ((1u << options.position_bits) - 1);
  result->position_error_bound_m = 0.5 * std::sqrt(3.0) * step;
  // Allow for float rounding of large coordinates on top of half a step.
  double largest = 0.0;
  for (const auto& p : originals)
    largest = std::max(largest, p.template cast<double>().cwiseAbs().maxCoeff());
  return result->position_error_bound_m + 8.0 * largest * 1.2e-7;
}

template <typename Vector>
void measure_error(const std::vector<Vector>& originals, const std::vector<bool>* used,
                   const std::vector<Eigen::Vector3f>& decoded, const DracoOptions& options,
                   DracoEncoded* result) {
  const double tolerance = error_tolerance(originals, options, result);
  const double step = result->position_range_m / ((1u << options.position_bits) - 1);
  result->max_position_error_m = max_nearest_distance(originals, used, decoded, step, tolerance);
  result->error_method = "nearest_decoded";
}

// The position Draco's decoder returns for each input position, computed with Draco's own
// float arithmetic: AttributeQuantizationTransform::ComputeParameters (per-axis minimum, range
// = largest extent, 1 when all points coincide), Quantizer (q = floor((p - min) *
// (2^bits - 1) / range + 0.5)) and Dequantizer (q * range / (2^bits - 1) + min), as in
// draco/attributes/attribute_quantization_transform.cc and draco/core/quantization_utils.cc.
class DracoPositionReplica {
 public:
  DracoPositionReplica(const std::vector<Eigen::Vector3f>& positions, int bits) {
    Eigen::Vector3f hi = positions[0];
    min_ = positions[0];
    for (const auto& p : positions) {
      min_ = min_.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    float range = 0.f;
    for (int c = 0; c < 3; ++c) range = std::max(range, hi[c] - min_[c]);
    if (range == 0.f) range = 1.f;
    const auto max_quantized = static_cast<int32_t>((1u << bits) - 1);
    inverse_delta_ = static_cast<float>(max_quantized) / range;
    delta_ = range / static_cast<float>(max_quantized);
  }
  Eigen::Vector3f decoded(const Eigen::Vector3f& p) const {
    Eigen::Vector3f out;
    for (int c = 0; c < 3; ++c) {
      float value = p[c] - min_[c];
      value *= inverse_delta_;
      const auto q = static_cast<int32_t>(std::floor(value + 0.5f));
      float back = static_cast<float>(q) * delta_;
      back = back + min_[c];
      out[c] = back;
    }
    return out;
  }

 private:
  Eigen::Vector3f min_;
  float inverse_delta_ = 1.f, delta_ = 1.f;
};

// Order-independent digest of a multiset of float triples: two sums (mod 2^64) of independent
// 64-bit mixes of the bit patterns. Equal multisets give equal digests; unequal ones collide
// with probability ~2^-128.
class MultisetDigest {
 public:
  void add(const Eigen::Vector3f& p) {
    uint32_t bits[3];
    for (int c = 0; c < 3; ++c) {
      const float value = p[c] + 0.0f;  // -0 and +0 are the same position
      std::memcpy(&bits[c], &value, sizeof(float));
    }
    const uint64_t xy = (static_cast<uint64_t>(bits[0]) << 32) | bits[1];
    sum_a_ += mix(xy ^ mix(bits[2] + 0x9e3779b97f4a7c15ULL));
    sum_b_ += mix(mix(xy + 0xd1b54a32d192ed03ULL) ^ (bits[2] * 0xc2b2ae3d27d4eb4fULL));
    ++count_;
  }
  bool operator==(const MultisetDigest& other) const {
    return sum_a_ == other.sum_a_ && sum_b_ == other.sum_b_ && count_ == other.count_;
  }

 private:
  static uint64_t mix(uint64_t x) {  // splitmix64 finalizer
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
  }
  uint64_t sum_a_ = 0, sum_b_ = 0, count_ = 0;
};

// The point cloud's error without a spatial search: each input position's decoded value is
// predicted by DracoPositionReplica, and the prediction is accepted only when the multiset of
// predicted positions equals the multiset Draco actually decoded (MultisetDigest). Then every
// decoded point is exactly the quantization of an input point, and the largest |predicted -
// original| is the largest error. O(n) time, O(1) memory. Returns false (nothing measured)
// when the decoded points differ from the prediction.
bool measure_error_by_replica(const std::vector<Eigen::Vector3f>& originals,
                              const draco::PointCloud& decoded, const DracoOptions& options,
                              double tolerance, DracoEncoded* result) {
  const draco::PointAttribute* position =
      decoded.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (position == nullptr || position->num_components() != 3) return false;
  MultisetDigest actual;
  for (draco::PointIndex i(0); i < decoded.num_points(); ++i) {
    Eigen::Vector3f p;
    position->ConvertValue<float>(position->mapped_index(i), 3, p.data());
    actual.add(p);
  }
  const DracoPositionReplica replica(originals, options.position_bits);
  MultisetDigest predicted;
  double max_squared = 0.0;
  for (const Eigen::Vector3f& p : originals) {
    const Eigen::Vector3f d = replica.decoded(p);
    predicted.add(d);
    max_squared = std::max(max_squared, (d.cast<double>() - p.cast<double>()).squaredNorm());
  }
  if (!(predicted == actual)) return false;
  const double max_error = std::sqrt(max_squared);
  if (max_error > tolerance) {
    throw std::runtime_error("draco round trip: a point moved " + std::to_string(max_error) +
                             " m, more than the quantization bound " + std::to_string(tolerance) +
                             " m");
  }
  result->max_position_error_m = max_error;
  result->error_method = "replica";
  return true;
}

std::string to_string(const draco::EncoderBuffer& buffer) {
  return std::string(buffer.data(), buffer.size());
}

void check_status(const draco::Status& status, const std::string& what) {
  if (!status.ok()) throw std::runtime_error(what + ": " + status.error_msg_string());
}

std::vector<Eigen::Vector3f> read_positions(const draco::PointCloud& geometry,
                                            const std::string& what) {
  const draco::PointAttribute* position =
      geometry.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (position == nullptr || position->num_components() != 3) {
    throw std::runtime_error(what + ": draco geometry has no 3D position attribute");
  }
  std::vector<Eigen::Vector3f> positions(geometry.num_points());
  for (draco::PointIndex i(0); i < geometry.num_points(); ++i) {
    position->ConvertValue<float>(position->mapped_index(i), 3, positions[i.value()].data());
  }
  return positions;
}

std::vector<ScalarField> read_fields(const draco::PointCloud& geometry) {
  std::vector<ScalarField> fields;
  for (int a = 0; a < geometry.num_attributes(); ++a) {
    const draco::PointAttribute* attribute = geometry.attribute(a);
    if (attribute->attribute_type() != draco::GeometryAttribute::GENERIC ||
        attribute->num_components() != 1) {
      continue;
    }
    ScalarField field;
    const draco::AttributeMetadata* metadata = geometry.GetAttributeMetadataByAttributeId(a);
    if (metadata == nullptr || !metadata->GetEntryString(kNameEntry, &field.name)) {
      field.name = "generic_" + std::to_string(a);
    }
    field.values.resize(geometry.num_points());
    for (draco::PointIndex i(0); i < geometry.num_points(); ++i) {
      attribute->ConvertValue<float>(attribute->mapped_index(i), 1, &field.values[i.value()]);
    }
    fields.push_back(std::move(field));
  }
  return fields;
}

draco::StatusOr<std::unique_ptr<draco::PointCloud>> decode_cloud(const std::string& bytes) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  return decoder.DecodePointCloudFromBuffer(&buffer);
}

void add_scalar_attribute(draco::Mesh* mesh, const ScalarField& field) {
  draco::GeometryAttribute attribute;
  attribute.Init(draco::GeometryAttribute::GENERIC, nullptr, 1, draco::DT_FLOAT32, false,
                 sizeof(float), 0);
  const int id = mesh->AddAttribute(attribute, true, field.values.size());
  for (size_t i = 0; i < field.values.size(); ++i) {
    mesh->attribute(id)->SetAttributeValue(draco::AttributeValueIndex(i), &field.values[i]);
  }
  name_attribute(mesh, id, field.name);
}

}  // namespace

DracoEncoded encode_draco_point_cloud(const std::vector<Eigen::Vector3f>& positions,
                                      const std::vector<ScalarField>& fields,
                                      const DracoOptions& options) {
  check_options(options);
  check_positions(positions, "encode_draco_point_cloud");
  check_scalar_fields(fields, positions.size(), {});

  draco::PointCloudBuilder builder;
  builder.Start(static_cast<draco::PointIndex::ValueType>(positions.size()));
  const int position_id =
      builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  // Eigen::Vector3f is three packed floats, so the vector is the interleaved buffer.
  builder.SetAttributeValuesForAllPoints(position_id, positions.data(), sizeof(Eigen::Vector3f));
  std::vector<int> field_ids;
  for (const auto& field : fields) {
    field_ids.push_back(
        builder.AddAttribute(draco::GeometryAttribute::GENERIC, 1, draco::DT_FLOAT32));
    builder.SetAttributeValuesForAllPoints(field_ids.back(), field.values.data(), sizeof(float));
  }
  std::unique_ptr<draco::PointCloud> cloud = builder.Finalize(false);
  for (size_t f = 0; f < fields.size(); ++f)
    name_attribute(cloud.get(), field_ids[f], fields[f].name);

  draco::Encoder encoder = make_encoder(options);
  draco::EncoderBuffer buffer;
  check_status(encoder.EncodePointCloudToBuffer(*cloud, &buffer), "draco point cloud encoding");

  cloud.reset();  // the encoder's copy of the input is no longer needed

  DracoEncoded result;
  result.bytes = to_string(buffer);
  buffer.Clear();
  auto decoded = decode_cloud(result.bytes);
  check_status(decoded.status(), "encoded point cloud: not a valid Draco geometry");
  const draco::PointCloud& decoded_cloud = *decoded.value();
  if (decoded_cloud.num_points() != positions.size()) {
    throw std::runtime_error("draco round trip: " + std::to_string(positions.size()) +
                             " points encoded, " + std::to_string(decoded_cloud.num_points()) +
                             " decoded");
  }
  const double tolerance = error_tolerance(positions, options, &result);
  if (!measure_error_by_replica(positions, decoded_cloud, options, tolerance, &result)) {
    // Draco quantized differently from the replica (another Draco version, say): match each
    // input point to its nearest decoded point instead.
    measure_error(positions, nullptr, read_positions(decoded_cloud, "encoded point cloud"), options,
                  &result);
  }
  return result;
}

DracoEncoded encode_draco_point_cloud(const PointCloud& cloud,
                                      const std::vector<ScalarField>& fields,
                                      const DracoOptions& options) {
  if (!cloud.has_intensity()) return encode_draco_point_cloud(cloud.xyz, fields, options);
  std::vector<ScalarField> with_intensity{{"intensity", cloud.intensity}};
  with_intensity.insert(with_intensity.end(), fields.begin(), fields.end());
  return encode_draco_point_cloud(cloud.xyz, with_intensity, options);
}

DracoEncoded encode_draco_mesh(const TriangleMesh& mesh,
                               const std::vector<ScalarField>& vertex_fields,
                               const DracoOptions& options) {
  check_options(options);
  check_positions(mesh.vertices, "encode_draco_mesh");
  check_scalar_fields(vertex_fields, mesh.vertices.size(), {});
  if (mesh.faces.empty()) throw std::invalid_argument("encode_draco_mesh: mesh has no faces");
  const int num_vertices = static_cast<int>(mesh.vertices.size());
  std::vector<bool> used(mesh.vertices.size(), false);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    if ((face.array() < 0).any() || (face.array() >= num_vertices).any()) {
      throw std::invalid_argument("encode_draco_mesh: face " + std::to_string(f) +
                                  " has a vertex index outside [0, " +
                                  std::to_string(num_vertices) + ")");
    }
    // Draco's corner table drops faces that repeat a vertex, and with them vertices only
    // such faces use: those are not measured.
    if (face[0] != face[1] && face[1] != face[2] && face[0] != face[2]) {
      for (int c = 0; c < 3; ++c) used[face[c]] = true;
    }
  }

  draco::Mesh draco_mesh;
  draco_mesh.set_num_points(static_cast<draco::PointIndex::ValueType>(num_vertices));
  draco::GeometryAttribute position;
  position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false,
                3 * sizeof(float), 0);
  const int position_id = draco_mesh.AddAttribute(position, true, num_vertices);
  for (int i = 0; i < num_vertices; ++i) {
    const Eigen::Vector3f p = mesh.vertices[i].cast<float>();
    draco_mesh.attribute(position_id)->SetAttributeValue(draco::AttributeValueIndex(i), p.data());
  }
  for (const auto& field : vertex_fields) add_scalar_attribute(&draco_mesh, field);
  draco_mesh.SetNumFaces(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    draco_mesh.SetFace(
        draco::FaceIndex(static_cast<uint32_t>(f)),
        {draco::PointIndex(face[0]), draco::PointIndex(face[1]), draco::PointIndex(face[2])});
  }

  draco::Encoder encoder = make_encoder(options);
  draco::EncoderBuffer buffer;
  check_status(encoder.EncodeMeshToBuffer(draco_mesh, &buffer), "draco mesh encoding");

  DracoEncoded result;
  result.bytes = to_string(buffer);
  const DracoMesh decoded = decode_draco_mesh(result.bytes, "encoded mesh");
  std::vector<Eigen::Vector3f> decoded_positions;
  decoded_positions.reserve(decoded.mesh.vertices.size());
  for (const auto& v : decoded.mesh.vertices) decoded_positions.push_back(v.cast<float>());
  measure_error(mesh.vertices, &used, decoded_positions, options, &result);
  return result;
}

DracoPointCloud decode_draco_point_cloud(const std::string& bytes, const std::string& what) {
  auto decoded = decode_cloud(bytes);
  check_status(decoded.status(), what + ": not a valid Draco geometry");
  const draco::PointCloud& cloud = *decoded.value();
  return {read_positions(cloud, what), read_fields(cloud)};
}

DracoMesh decode_draco_mesh(const std::string& bytes, const std::string& what) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  const auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
  check_status(type.status(), what + ": not a valid Draco geometry");
  if (type.value() != draco::TRIANGULAR_MESH) {
    throw std::runtime_error(what + ": Draco geometry is a point cloud, expected a mesh");
  }
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  check_status(decoded.status(), what + ": not a valid Draco mesh");
  const draco::Mesh& draco_mesh = *decoded.value();

  DracoMesh result;
  for (const auto& p : read_positions(draco_mesh, what)) {
    result.mesh.vertices.push_back(p.cast<double>());
  }
  result.mesh.faces.reserve(draco_mesh.num_faces());
  for (draco::FaceIndex f(0); f < draco_mesh.num_faces(); ++f) {
    const auto& face = draco_mesh.face(f);
    result.mesh.faces.emplace_back(face[0].value(), face[1].value(), face[2].value());
  }
  result.fields = read_fields(draco_mesh);
  return result;
}

void write_draco_file(const std::filesystem::path& path, const std::string& bytes) {
  std::filesystem::path temporary = path;
  temporary += ".partial";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path.string() + ": cannot open for writing");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw std::runtime_error(path.string() + ": write failed (disk full?)");
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    throw std::runtime_error(path.string() +
                             ": cannot move the written file into place: " + error.message());
  }
}

std::string read_draco_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad()) throw std::runtime_error(path.string() + ": read error");
  return std::move(bytes).str();
}

}  // namespace keel::io
