#include "worker/io/draco/draco_summary.h"

#include <draco/compression/decode.h>
#include <draco/mesh/mesh.h>
#include <draco/metadata/geometry_metadata.h>
#include <draco/point_cloud/point_cloud.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "worker/io/draco/draco_geometry_summary.h"
#include "worker/io/draco/draco_header_check.h"

namespace keel::io {

namespace {

const char* type_name(draco::DataType type) {
  switch (type) {
    case draco::DT_INT8:
      return "int8";
    case draco::DT_UINT8:
      return "uint8";
    case draco::DT_INT16:
      return "int16";
    case draco::DT_UINT16:
      return "uint16";
    case draco::DT_INT32:
      return "int32";
    case draco::DT_UINT32:
      return "uint32";
    case draco::DT_INT64:
      return "int64";
    case draco::DT_UINT64:
      return "uint64";
    case draco::DT_FLOAT32:
      return "float32";
    case draco::DT_FLOAT64:
      return "float64";
    case draco::DT_BOOL:
      return "bool";
    default:
      return "invalid";
  }
}

// Per-component minimum and maximum of the value every point holds, leaving out `no_data`. Reads
// the decoder's buffer directly when it is one packed value per point (float32 or uint8), else
// converts per point.
void value_range(const draco::PointAttribute& attribute, uint32_t points, double* min, double* max,
                 std::optional<double> no_data = std::nullopt) {
  const int n = attribute.num_components();
  for (int c = 0; c < n; ++c) {
    min[c] = std::numeric_limits<double>::infinity();
    max[c] = -std::numeric_limits<double>::infinity();
  }
  const bool packed = attribute.is_mapping_identity() &&
                      attribute.byte_stride() == n * draco::DataTypeLength(attribute.data_type());
  if (packed && attribute.data_type() == draco::DT_FLOAT32 && !no_data) {
    const uint8_t* data = attribute.GetAddress(draco::AttributeValueIndex(0));
    std::vector<float> lo(n, std::numeric_limits<float>::infinity()), hi(n, -lo[0]);
    float value[4];
    for (uint32_t i = 0; i < points; ++i) {
      std::memcpy(value, data + sizeof(float) * n * i, sizeof(float) * n);
      for (int c = 0; c < n; ++c)
        lo[c] = std::min(lo[c], value[c]), hi[c] = std::max(hi[c], value[c]);
    }
    for (int c = 0; c < n; ++c) min[c] = lo[c], max[c] = hi[c];
    return;
  }
  if (packed && attribute.data_type() == draco::DT_UINT8 && !no_data) {
    const uint8_t* data = attribute.GetAddress(draco::AttributeValueIndex(0));
    for (uint32_t i = 0; i < points; ++i)
      for (int c = 0; c < n; ++c) {
        min[c] = std::min<double>(min[c], data[n * i + c]);
        max[c] = std::max<double>(max[c], data[n * i + c]);
      }
    return;
  }
  std::vector<double> value(n);
  for (draco::PointIndex i(0); i < points; ++i) {
    attribute.ConvertValue<double>(attribute.mapped_index(i), n, value.data());
    for (int c = 0; c < n; ++c) {
      if (no_data && value[c] == *no_data) continue;
      min[c] = std::min(min[c], value[c]), max[c] = std::max(max[c], value[c]);
    }
  }
}

std::vector<std::string> labels_of(const draco::AttributeMetadata* metadata) {
  std::string text;
  if (metadata == nullptr || !metadata->GetEntryString(kDracoLabelsEntry, &text)) return {};
  const auto labels = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  std::vector<std::string> out;
  if (!labels.is_array()) return out;
  for (const auto& label : labels) out.push_back(label.is_string() ? label.get<std::string>() : "");
  return out;
}

std::optional<double> no_data_of(const draco::AttributeMetadata* metadata) {
  std::string text;
  if (metadata == nullptr || !metadata->GetEntryString(kDracoNoDataEntry, &text)) return {};
  const auto value = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!value.is_number()) return {};
  // The decoder returns float32 values: compare with the float the encoder stored.
  return static_cast<double>(value.get<float>());
}

}  // namespace

DracoSummary summarize_geometry(const draco::PointCloud& geometry, bool is_mesh, size_t faces) {
  DracoSummary out;
  out.kind = is_mesh ? "mesh" : "point_cloud";
  out.points = geometry.num_points();
  out.faces = faces;
  for (int a = 0; a < geometry.num_attributes(); ++a) {
    const draco::PointAttribute& attribute = *geometry.attribute(a);
    if (attribute.num_components() < 1 || attribute.num_components() > 4) continue;
    double min[4], max[4];
    if (attribute.attribute_type() == draco::GeometryAttribute::POSITION &&
        attribute.num_components() == 3) {
      value_range(attribute, geometry.num_points(), min, max);
      out.bbox_min = Eigen::Vector3d(min[0], min[1], min[2]);
      out.bbox_max = Eigen::Vector3d(max[0], max[1], max[2]);
      out.position_unique_id = static_cast<int>(attribute.unique_id());
      continue;
    }
    if (attribute.attribute_type() != draco::GeometryAttribute::GENERIC) continue;
    DracoAttributeSummary s;
    const draco::AttributeMetadata* metadata = geometry.GetAttributeMetadataByAttributeId(a);
    if (metadata == nullptr || !metadata->GetEntryString("name", &s.name))
      s.name = "generic_" + std::to_string(a);
    s.unique_id = static_cast<int>(attribute.unique_id());
    s.data_type = type_name(attribute.data_type());
    s.components = attribute.num_components();
    s.no_data = no_data_of(metadata);
    value_range(attribute, geometry.num_points(), min, max, s.no_data);
    s.min = *std::min_element(min, min + s.components);
    s.max = *std::max_element(max, max + s.components);
    if (!(s.min <= s.max)) s.min = s.max = std::nan("");
    s.labels = labels_of(metadata);
    out.attributes.push_back(std::move(s));
  }
  return out;
}

DracoSummary summarize_draco(const std::string& bytes, const std::string& what) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  const auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
  if (!type.ok()) throw std::runtime_error(what + ": not a valid Draco geometry");
  check_draco_header(bytes, what);  // before Draco allocates what the header declares
  draco::Decoder decoder;
  if (type.value() == draco::TRIANGULAR_MESH) {
    auto mesh = decoder.DecodeMeshFromBuffer(&buffer);
    if (!mesh.ok())
      throw std::runtime_error(what +
                               ": not a valid Draco mesh: " + mesh.status().error_msg_string());
    return summarize_geometry(*mesh.value(), true, mesh.value()->num_faces());
  }
  auto cloud = decoder.DecodePointCloudFromBuffer(&buffer);
  if (!cloud.ok())
    throw std::runtime_error(
        what + ": not a valid Draco point cloud: " + cloud.status().error_msg_string());
  return summarize_geometry(*cloud.value(), false, 0);
}

}  // namespace keel::io
