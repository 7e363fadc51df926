// The summary of a Draco file (what the sidecars say) against a brute-force scan of the file
// decoded by Draco's own API: attributes found by unique id the way three.js's DRACOLoader finds
// them, each one's range over every decoded value, the box of the decoded positions, the label
// attribute's counts per part, and no_data kept out of the range but stored exactly.
#include "worker/io/draco/draco_summary.h"

#include <draco/compression/decode.h>
#include <draco/metadata/geometry_metadata.h>
#include <draco/point_cloud/point_cloud.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "tests/core/mesh_fixtures.h"
#include "worker/io/draco/draco_codec.h"

namespace keel::io {
namespace {

PointCloud random_part(size_t n, unsigned seed, float x0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  PointCloud cloud;
  for (size_t i = 0; i < n; ++i) {
    cloud.xyz.emplace_back(x0 + 10.f * u(rng), -3.f + 6.f * u(rng), 2.f * u(rng));
    cloud.intensity.push_back(255.f * u(rng));
  }
  return cloud;
}

std::unique_ptr<draco::PointCloud> decode(const std::string& bytes) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodePointCloudFromBuffer(&buffer);
  EXPECT_TRUE(decoded.ok());
  return std::move(decoded).value();
}

// Every point's value of a 1-component attribute, through Draco's own conversion.
std::vector<double> values_of(const draco::PointCloud& cloud, const draco::PointAttribute& a) {
  std::vector<double> out;
  for (draco::PointIndex i(0); i < cloud.num_points(); ++i) {
    double v = 0;
    a.ConvertValue<double>(a.mapped_index(i), 1, &v);
    out.push_back(v);
  }
  return out;
}

TEST(DracoSummary, PartsWithLabelAndFieldsMatchABruteForceScan) {
  const PointCloud a = random_part(700, 1, 0.f), empty, c = random_part(1300, 2, 40.f);
  PartsAttributes attributes;
  attributes.label_name = "sensor";
  attributes.part_labels = {"lidar_a", "lidar_b", "sonar"};
  // A field with some undefined points, marked by a no_data value below every defined one.
  ScalarField density{"density", {}};
  size_t undefined = 0;
  for (size_t i = 0; i < 2000; ++i) {
    const bool defined = i % 97 != 5;
    density.values.push_back(defined ? 100.f + 0.5f * static_cast<float>(i) : -7.f);
    undefined += !defined;
  }
  attributes.fields = {density};
  attributes.fields_no_data = {-7.f};
  DracoOptions options;
  options.position_bits = 14;
  options.field_bits = 10;
  const DracoEncoded encoded = encode_draco_point_cloud({&a, &empty, &c}, options, attributes);
  const DracoSummary summary = summarize_draco(encoded.bytes, "test");

  const auto cloud = decode(encoded.bytes);
  EXPECT_EQ(summary.kind, "point_cloud");
  EXPECT_EQ(summary.points, 2000u);
  EXPECT_EQ(summary.points, cloud->num_points());
  EXPECT_EQ(summary.faces, 0u);
  // The encoder's summary (from its round trip) is the file's.
  EXPECT_EQ(encoded.summary.attributes.size(), summary.attributes.size());
  EXPECT_EQ(encoded.summary.bbox_min, summary.bbox_min);
  EXPECT_EQ(encoded.summary.bbox_max, summary.bbox_max);

  // The box of the decoded positions.
  const draco::PointAttribute* position =
      cloud->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (draco::PointIndex i(0); i < cloud->num_points(); ++i) {
    double p[3];
    position->ConvertValue<double>(position->mapped_index(i), 3, p);
    lo = lo.cwiseMin(Eigen::Vector3d(p[0], p[1], p[2]));
    hi = hi.cwiseMax(Eigen::Vector3d(p[0], p[1], p[2]));
  }
  EXPECT_EQ(summary.bbox_min, lo);
  EXPECT_EQ(summary.bbox_max, hi);
  EXPECT_EQ(summary.position_unique_id, static_cast<int>(position->unique_id()));

  ASSERT_EQ(summary.attributes.size(), 3u);  // intensity, density, sensor
  for (const DracoAttributeSummary& s : summary.attributes) {
    SCOPED_TRACE(s.name);
    // Found by unique id, as DRACOLoader does, with the name the summary gives.
    const draco::PointAttribute* attribute = cloud->GetAttributeByUniqueId(s.unique_id);
    ASSERT_NE(attribute, nullptr);
    std::string name;
    ASSERT_TRUE(cloud->GetMetadata()
                    ->GetAttributeMetadataByUniqueId(s.unique_id)
                    ->GetEntryString("name", &name));
    EXPECT_EQ(name, s.name);
    double min = INFINITY, max = -INFINITY;
    size_t no_data = 0;
    for (double v : values_of(*cloud, *attribute)) {
      if (s.no_data && v == *s.no_data) {
        ++no_data;
        continue;
      }
      min = std::min(min, v), max = std::max(max, v);
    }
    EXPECT_EQ(s.min, min);
    EXPECT_EQ(s.max, max);
    if (s.name == "density") {
      ASSERT_TRUE(s.no_data.has_value());
      EXPECT_EQ(*s.no_data, -7.0);
      EXPECT_EQ(no_data, undefined);  // stored exactly: it is the quantized minimum
      EXPECT_NEAR(s.min, 100.0, (1099.5 + 7.0) / 1023);  // within a quantization step
    }
  }
  const DracoAttributeSummary& sensor = summary.attributes[2];
  EXPECT_EQ(sensor.name, "sensor");
  EXPECT_EQ(sensor.data_type, "uint8");
  EXPECT_EQ(sensor.labels, attributes.part_labels);
  EXPECT_EQ(sensor.min, 0.0);
  EXPECT_EQ(sensor.max, 2.0);  // the empty part's label 1 holds no point
  std::vector<size_t> per_label(3, 0);
  for (double v : values_of(*cloud, *cloud->GetAttributeByUniqueId(sensor.unique_id)))
    ++per_label[static_cast<size_t>(v)];
  EXPECT_EQ(per_label, (std::vector<size_t>{700, 0, 1300}));
  EXPECT_EQ(summary.attributes[0].name, "intensity");
  EXPECT_FALSE(summary.attributes[0].no_data.has_value());
}

TEST(DracoSummary, MeshCountsAndFieldRangeMatchTheDecodedMesh) {
  const TriangleMesh mesh = keel::testing::make_icosphere(3, 2.0);
  ScalarField deviation{"deviation", {}};
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    deviation.values.push_back(0.01f * std::sin(static_cast<float>(i)));
  const DracoEncoded encoded = encode_draco_mesh(mesh, {deviation}, DracoOptions{});
  const DracoSummary summary = summarize_draco(encoded.bytes);
  const DracoMesh decoded = decode_draco_mesh(encoded.bytes);
  EXPECT_EQ(summary.kind, "mesh");
  EXPECT_EQ(summary.faces, decoded.mesh.faces.size());
  EXPECT_EQ(summary.points, decoded.mesh.vertices.size());
  ASSERT_EQ(summary.attributes.size(), 1u);
  ASSERT_EQ(decoded.fields.size(), 1u);
  const auto& values = decoded.fields[0].values;
  EXPECT_EQ(summary.attributes[0].min, *std::min_element(values.begin(), values.end()));
  EXPECT_EQ(summary.attributes[0].max, *std::max_element(values.begin(), values.end()));
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const auto& v : decoded.mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  EXPECT_EQ(summary.bbox_min, lo);
  EXPECT_EQ(summary.bbox_max, hi);
  EXPECT_EQ(encoded.summary.faces, summary.faces);
}

TEST(DracoSummary, BadBytesNameWhatTheyAre) {
  try {
    summarize_draco("not a draco file", "map_x.drc");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("map_x.drc"), std::string::npos) << e.what();
  }
}

TEST(DracoSummary, LabelsMustMatchTheParts) {
  const PointCloud a = random_part(10, 3, 0.f);
  PartsAttributes attributes;
  attributes.label_name = "sensor";
  attributes.part_labels = {"a", "b"};
  EXPECT_THROW(encode_draco_point_cloud({&a}, DracoOptions{}, attributes), std::invalid_argument);
}

}  // namespace
}  // namespace keel::io
