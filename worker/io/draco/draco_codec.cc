#include "worker/io/draco/draco_codec.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#include <draco/metadata/geometry_metadata.h>
#include <draco/point_cloud/point_cloud.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <new>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/replaced_file.h"
#include "worker/io/draco/draco_geometry_summary.h"
#include "worker/io/draco/draco_position_error.h"

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
void check_finite(const std::vector<Vector>& positions, const char* what, size_t first_index) {
  for (size_t i = 0; i < positions.size(); ++i) {
    if (!positions[i].allFinite()) {
      throw std::invalid_argument(std::string(what) + ": position " +
                                  std::to_string(first_index + i) + " is not finite (NaN or inf)");
    }
  }
}

template <typename Vector>
void check_positions(const std::vector<Vector>& positions, const char* what) {
  if (positions.empty()) throw std::invalid_argument(std::string(what) + ": no points to encode");
  check_finite(positions, what, 0);
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

void name_attribute(draco::PointCloud* geometry, int attribute_id, const std::string& name,
                    const std::vector<std::string>& labels = {},
                    std::optional<float> no_data = std::nullopt) {
  auto metadata = std::make_unique<draco::AttributeMetadata>();
  metadata->AddEntryString(kNameEntry, name);
  if (!labels.empty()) metadata->AddEntryString(kDracoLabelsEntry, nlohmann::json(labels).dump());
  if (no_data) metadata->AddEntryString(kDracoNoDataEntry, nlohmann::json(*no_data).dump());
  geometry->AddAttributeMetadata(attribute_id, std::move(metadata));
}

std::string to_string(const draco::EncoderBuffer& buffer) {
  return std::string(buffer.data(), buffer.size());
}

void check_status(const draco::Status& status, const std::string& what) {
  if (!status.ok()) throw std::runtime_error(what + ": " + status.error_msg_string());
}

// One value of `attribute` (`count` components) as floats. Draco's ConvertValue<float> loads a
// bool attribute's bytes as bool (undefined for bytes other than 0 and 1: fuzz_draco found
// one) and casts doubles to float unchecked (undefined beyond float's range); those two types
// are read here, the others through Draco. False when a value lies outside the attribute's
// buffer or float's range.
bool values_as_float(const draco::PointAttribute& attribute, draco::AttributeValueIndex index,
                     int count, float* out) {
  const auto type = attribute.data_type();
  if (type != draco::DT_BOOL && type != draco::DT_FLOAT64) {
    return attribute.ConvertValue<float>(index, static_cast<int8_t>(count), out);
  }
  const size_t size = type == draco::DT_BOOL ? 1 : sizeof(double);
  const uint8_t* address = attribute.GetAddress(index);
  for (int c = 0; c < count; ++c, address += size) {
    if (!attribute.IsAddressValid(address + size - 1)) return false;
    if (type == draco::DT_BOOL) {
      out[c] = *address != 0 ? 1.0f : 0.0f;
      continue;
    }
    double value;
    std::memcpy(&value, address, sizeof(value));
    if (std::isfinite(value) && std::abs(value) > std::numeric_limits<float>::max()) return false;
    out[c] = static_cast<float>(value);
  }
  return true;
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
    if (!values_as_float(*position, position->mapped_index(i), 3, positions[i.value()].data()))
      throw std::runtime_error(what + ": Draco position " + std::to_string(i.value()) +
                               " is not a float value");
  }
  return positions;
}

std::vector<ScalarField> read_fields(const draco::PointCloud& geometry, const std::string& what) {
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
      if (!values_as_float(*attribute, attribute->mapped_index(i), 1, &field.values[i.value()]))
        throw std::runtime_error(what + ": Draco field '" + field.name + "' value " +
                                 std::to_string(i.value()) + " is not a float value");
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

// A scalar field of a cloud given as parts: its values in each part, in part order.
struct FieldParts {
  std::string name;
  std::vector<const std::vector<float>*> parts;
  std::optional<float> no_data;
};

// Appends each part's values to the attribute's buffer (one contiguous block per part, as
// draco::PointCloudBuilder::SetAttributeValuesForAllPoints writes a whole cloud).
template <typename Value>
void fill_attribute(draco::PointAttribute* attribute,
                    const std::vector<const std::vector<Value>*>& parts) {
  int64_t offset = 0;
  for (const std::vector<Value>* part : parts) {
    const size_t bytes = part->size() * sizeof(Value);
    attribute->buffer()->Write(offset, part->data(), bytes);
    offset += static_cast<int64_t>(bytes);
  }
}

int add_attribute(draco::PointCloud* cloud, draco::GeometryAttribute::Type type, int components) {
  draco::GeometryAttribute attribute;
  attribute.Init(type, nullptr, components, draco::DT_FLOAT32, false, sizeof(float) * components,
                 0);
  return cloud->AddAttribute(attribute, true, cloud->num_points());
}

// A label attribute over parts: `counts[k]` points holding `values[k]`, in part order.
struct LabelParts {
  std::string name;
  std::vector<std::string> labels;
  std::vector<size_t> counts;
  std::vector<uint8_t> values;
};

void add_label_attribute(draco::PointCloud* cloud, const LabelParts& label) {
  draco::GeometryAttribute attribute;
  attribute.Init(draco::GeometryAttribute::GENERIC, nullptr, 1, draco::DT_UINT8, false, 1, 0);
  const int id = cloud->AddAttribute(attribute, true, cloud->num_points());
  int64_t offset = 0;
  for (size_t k = 0; k < label.counts.size(); ++k) {
    const std::vector<uint8_t> block(std::min<size_t>(label.counts[k], 1 << 16), label.values[k]);
    for (size_t done = 0; done < label.counts[k]; done += block.size()) {
      const size_t n = std::min(block.size(), label.counts[k] - done);
      cloud->attribute(id)->buffer()->Write(offset, block.data(), n);
      offset += static_cast<int64_t>(n);
    }
  }
  name_attribute(cloud, id, label.name, label.labels);
}

// The encoding of the concatenated parts (the same draco::PointCloud, hence the same bytes as
// encoding the concatenated cloud); `bytes` only.
DracoEncoded encode_cloud_bytes(const PositionParts& positions,
                                const std::vector<FieldParts>& fields, const DracoOptions& options,
                                const LabelParts* label = nullptr) {
  check_options(options);
  size_t n = 0;
  for (const std::vector<Eigen::Vector3f>* part : positions) n += part->size();
  if (n == 0) throw std::invalid_argument("encode_draco_point_cloud: no points to encode");
  size_t offset = 0;
  for (const std::vector<Eigen::Vector3f>* part : positions) {
    check_finite(*part, "encode_draco_point_cloud", offset);
    offset += part->size();
  }

  auto cloud = std::make_unique<draco::PointCloud>();
  cloud->set_num_points(static_cast<draco::PointIndex::ValueType>(n));
  // Eigen::Vector3f is three packed floats, so each part is an interleaved buffer.
  fill_attribute(
      cloud->attribute(add_attribute(cloud.get(), draco::GeometryAttribute::POSITION, 3)),
      positions);
  for (const auto& field : fields) {
    const int id = add_attribute(cloud.get(), draco::GeometryAttribute::GENERIC, 1);
    fill_attribute(cloud->attribute(id), field.parts);
    name_attribute(cloud.get(), id, field.name, {}, field.no_data);
  }
  if (label != nullptr) add_label_attribute(cloud.get(), *label);

  draco::Encoder encoder = make_encoder(options);
  draco::EncoderBuffer buffer;
  check_status(encoder.EncodePointCloudToBuffer(*cloud, &buffer), "draco point cloud encoding");

  cloud.reset();  // the encoder's copy of the input is no longer needed

  DracoEncoded result;
  result.bytes = to_string(buffer);
  return result;
}

// The round trip of encode_cloud_bytes' result: decode, compare, measure the error.
void measure_cloud(const PositionParts& positions, const DracoOptions& options,
                   DracoEncoded* encoded) {
  DracoEncoded& result = *encoded;
  size_t n = 0;
  for (const std::vector<Eigen::Vector3f>* part : positions) n += part->size();
  auto decoded = decode_cloud(result.bytes);
  check_status(decoded.status(), "encoded point cloud: not a valid Draco geometry");
  const draco::PointCloud& decoded_cloud = *decoded.value();
  if (decoded_cloud.num_points() != n) {
    throw std::runtime_error("draco round trip: " + std::to_string(n) + " points encoded, " +
                             std::to_string(decoded_cloud.num_points()) + " decoded");
  }
  result.summary = summarize_geometry(decoded_cloud, false, 0);
  const PositionBounds bounds = position_bounds(positions);
  const double tolerance = error_tolerance(bounds, options, &result);
  if (!measure_error_by_replica(positions, bounds, decoded_cloud, options, tolerance, &result)) {
    // Draco quantized differently from the replica (another Draco version, say): match each
    // input point to its nearest decoded point instead.
    std::vector<Eigen::Vector3f> originals;
    originals.reserve(n);
    for (const std::vector<Eigen::Vector3f>* part : positions)
      originals.insert(originals.end(), part->begin(), part->end());
    measure_error(originals, nullptr, read_positions(decoded_cloud, "encoded point cloud"), options,
                  &result);
  }
}

DracoEncoded encode_cloud_parts(const PositionParts& positions,
                                const std::vector<FieldParts>& fields, const DracoOptions& options,
                                const LabelParts* label = nullptr) {
  DracoEncoded result = encode_cloud_bytes(positions, fields, options, label);
  measure_cloud(positions, options, &result);
  return result;
}

// A cloud given as parts: positions, intensity when every non-empty part has it, and the
// PartsAttributes (a label, whole-cloud fields).
struct CloudParts {
  PositionParts positions;
  std::vector<FieldParts> fields;
  std::optional<LabelParts> label;
};

CloudParts cloud_parts(const std::vector<const PointCloud*>& parts,
                       const PartsAttributes& attributes = {}) {
  CloudParts out;
  FieldParts intensity{"intensity", {}, std::nullopt};
  bool all_intensity = true;
  for (const PointCloud* part : parts) {
    if (part->empty()) continue;
    if (part->has_intensity() && part->intensity.size() != part->size())
      throw std::invalid_argument("encode_draco_point_cloud: a part has " +
                                  std::to_string(part->intensity.size()) + " intensities for " +
                                  std::to_string(part->size()) + " points");
    out.positions.push_back(&part->xyz);
    intensity.parts.push_back(&part->intensity);
    all_intensity = all_intensity && part->has_intensity();
  }
  if (out.positions.empty())
    throw std::invalid_argument("encode_draco_point_cloud: no points to encode");
  if (all_intensity) out.fields.push_back(std::move(intensity));
  size_t n = 0;
  for (const std::vector<Eigen::Vector3f>* part : out.positions) n += part->size();
  std::vector<std::string> reserved = {"intensity"};
  if (!attributes.label_name.empty()) reserved.push_back(attributes.label_name);
  check_scalar_fields(attributes.fields, n, reserved);
  if (!attributes.fields_no_data.empty() &&
      attributes.fields_no_data.size() != attributes.fields.size())
    throw std::invalid_argument(
        "encode_draco_point_cloud: " + std::to_string(attributes.fields_no_data.size()) +
        " no_data values for " + std::to_string(attributes.fields.size()) + " fields");
  for (size_t f = 0; f < attributes.fields.size(); ++f)
    out.fields.push_back(
        {attributes.fields[f].name,
         {&attributes.fields[f].values},
         attributes.fields_no_data.empty() || std::isnan(attributes.fields_no_data[f])
             ? std::nullopt
             : std::optional<float>(attributes.fields_no_data[f])});
  if (!attributes.label_name.empty()) {
    if (attributes.part_labels.size() != parts.size() || parts.size() > 256)
      throw std::invalid_argument("encode_draco_point_cloud: label '" + attributes.label_name +
                                  "' needs one label per part (at most 256), got " +
                                  std::to_string(attributes.part_labels.size()) + " for " +
                                  std::to_string(parts.size()) + " parts");
    LabelParts label{attributes.label_name, attributes.part_labels, {}, {}};
    for (size_t k = 0; k < parts.size(); ++k) {
      if (parts[k]->empty()) continue;
      label.counts.push_back(parts[k]->size());
      label.values.push_back(static_cast<uint8_t>(k));
    }
    out.label = std::move(label);
  }
  return out;
}

}  // namespace

DracoEncoded encode_draco_point_cloud(const std::vector<Eigen::Vector3f>& positions,
                                      const std::vector<ScalarField>& fields,
                                      const DracoOptions& options) {
  check_options(options);
  check_positions(positions, "encode_draco_point_cloud");
  check_scalar_fields(fields, positions.size(), {});
  std::vector<FieldParts> field_parts;
  for (const auto& field : fields)
    field_parts.push_back({field.name, {&field.values}, std::nullopt});
  return encode_cloud_parts({&positions}, field_parts, options);
}

DracoEncoded encode_draco_point_cloud(const PointCloud& cloud,
                                      const std::vector<ScalarField>& fields,
                                      const DracoOptions& options) {
  if (!cloud.has_intensity()) return encode_draco_point_cloud(cloud.xyz, fields, options);
  std::vector<ScalarField> with_intensity{{"intensity", cloud.intensity}};
  with_intensity.insert(with_intensity.end(), fields.begin(), fields.end());
  return encode_draco_point_cloud(cloud.xyz, with_intensity, options);
}

DracoEncoded encode_draco_point_cloud(const std::vector<const PointCloud*>& parts,
                                      const DracoOptions& options,
                                      const PartsAttributes& attributes) {
  const CloudParts cloud = cloud_parts(parts, attributes);
  return encode_cloud_parts(cloud.positions, cloud.fields, options,
                            cloud.label ? &*cloud.label : nullptr);
}

DracoEncoded encode_draco_point_cloud_bytes(const std::vector<const PointCloud*>& parts,
                                            const DracoOptions& options,
                                            const PartsAttributes& attributes) {
  const CloudParts cloud = cloud_parts(parts, attributes);
  return encode_cloud_bytes(cloud.positions, cloud.fields, options,
                            cloud.label ? &*cloud.label : nullptr);
}

void measure_draco_point_cloud(const std::vector<const PointCloud*>& parts,
                               const DracoOptions& options, DracoEncoded* encoded) {
  check_options(options);
  measure_cloud(cloud_parts(parts).positions, options, encoded);
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
  result.summary = summarize_draco(result.bytes, "encoded mesh");
  return result;
}

namespace {
// Draco sizes each attribute from the counts and component sizes the file declares: what the
// limits let through may still ask for more memory than the machine has.
template <class Decode>
auto decoding(const std::string& what, Decode&& decode) {
  try {
    return decode();
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(what +
                             ": Draco could not get the memory the file asks for; the "
                             "file is corrupt or larger than this machine decodes");
  }
}
}  // namespace

DracoPointCloud decode_draco_point_cloud(const std::string& bytes, const std::string& what,
                                         const DracoLimits& limits) {
  check_draco_header(bytes, what, limits);
  return decoding(what, [&]() -> DracoPointCloud {
    auto decoded = decode_cloud(bytes);
    check_status(decoded.status(), what + ": not a valid Draco geometry");
    const draco::PointCloud& cloud = *decoded.value();
    return {read_positions(cloud, what), read_fields(cloud, what)};
  });
}

DracoMesh decode_draco_mesh(const std::string& bytes, const std::string& what,
                            const DracoLimits& limits) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  const auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
  check_status(type.status(), what + ": not a valid Draco geometry");
  if (type.value() != draco::TRIANGULAR_MESH) {
    throw std::runtime_error(what + ": Draco geometry is a point cloud, expected a mesh");
  }
  check_draco_header(bytes, what, limits);
  return decoding(what, [&] {
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
    result.fields = read_fields(draco_mesh, what);
    return result;
  });
}

void write_draco_file(const std::filesystem::path& path, const std::string& bytes) {
  write_file_replacing(path, bytes);
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
