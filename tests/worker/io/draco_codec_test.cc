// Draco round trips: the position error is checked point by point through an `id` field
// (a correspondence the encoder itself does not use), against the quantization bound
// range / 2^bits and against the error the encoder reports.
#include "worker/io/draco/draco_codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <set>

#include <draco/compression/encode.h>
#include <draco/point_cloud/point_cloud.h>

#include "tests/core/mesh_fixtures.h"
#include "tests/worker/io/mesh_test_util.h"

namespace keel::io {
namespace {

const ScalarField* find_field(const std::vector<ScalarField>& fields, const std::string& name) {
  for (const auto& f : fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

std::vector<Eigen::Vector3f> random_points(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> x(-5.f, 20.f), y(0.f, 10.f), z(-2.f, 1.f);
  std::vector<Eigen::Vector3f> points;
  for (size_t i = 0; i < n; ++i) {  // one draw per statement: argument order is unspecified
    const float px = x(rng);
    const float py = y(rng);
    points.emplace_back(px, py, z(rng));
  }
  return points;
}

ScalarField id_field(size_t n) {
  ScalarField ids{"id", {}};
  for (size_t i = 0; i < n; ++i) ids.values.push_back(static_cast<float>(i));
  return ids;
}

TEST(DracoCodec, PointCloudErrorWithinQuantizationBoundAndEqualToReported) {
  constexpr size_t kPoints = 3000;
  const auto points = random_points(kPoints, 11);
  ScalarField density{"density", {}};
  for (size_t i = 0; i < kPoints; ++i) density.values.push_back(std::sin(0.01f * i));
  for (const int bits : {8, 11, 14, 16}) {
    SCOPED_TRACE("position_bits " + std::to_string(bits));
    DracoOptions options;
    options.position_bits = bits;
    options.field_bits = 0;  // ids and density lossless
    const DracoEncoded encoded =
        encode_draco_point_cloud(points, {id_field(kPoints), density}, options);
    const DracoPointCloud decoded = decode_draco_point_cloud(encoded.bytes);
    ASSERT_EQ(decoded.positions.size(), kPoints);
    const ScalarField* ids = find_field(decoded.fields, "id");
    const ScalarField* dens = find_field(decoded.fields, "density");
    ASSERT_NE(ids, nullptr);
    ASSERT_NE(dens, nullptr);
    double max_error = 0;
    std::set<int> seen;
    for (size_t k = 0; k < kPoints; ++k) {
      const int i = static_cast<int>(ids->values[k]);
      ASSERT_TRUE(i >= 0 && i < static_cast<int>(kPoints) && seen.insert(i).second);
      max_error =
          std::max<double>(max_error, (decoded.positions[k] - points[i]).cast<double>().norm());
      EXPECT_EQ(dens->values[k], density.values[i]);
    }
    // Draco quantizes over the largest extent of the bounding box: x's, within [-5, 20].
    double x_min = points[0].x(), x_max = points[0].x();
    for (const auto& p : points)
      x_min = std::min<double>(x_min, p.x()), x_max = std::max<double>(x_max, p.x());
    const double range = x_max - x_min;
    EXPECT_GT(range, 24.9);
    EXPECT_NEAR(encoded.position_range_m, range, 1e-5);
    EXPECT_LE(max_error, range / std::pow(2.0, bits));
    EXPECT_LE(max_error, encoded.position_error_bound_m * (1 + 1e-6));
    EXPECT_NEAR(encoded.max_position_error_m, max_error, 1e-6);
    EXPECT_GT(max_error, 0.2 * encoded.position_error_bound_m);  // quantization did happen
    EXPECT_EQ(encoded.error_method, "replica");  // the O(n) check, not the spatial search
  }
}

TEST(DracoCodec, ReplicaErrorMatchesPerPointErrorsOnALargeOffsetCloudWithDuplicates) {
  // Coordinates far from the origin (float rounding at the half-step boundaries) and repeated
  // points: the replica must still reproduce Draco's decoded multiset exactly.
  std::vector<Eigen::Vector3f> points = random_points(4000, 23);
  for (auto& p : points) p += Eigen::Vector3f(4.0e5f, -3.1e4f, 12.0f);
  for (size_t i = 0; i < 500; ++i) points.push_back(points[i]);
  DracoOptions options;
  options.position_bits = 18;
  options.field_bits = 0;
  const DracoEncoded encoded = encode_draco_point_cloud(points, {id_field(points.size())}, options);
  EXPECT_EQ(encoded.error_method, "replica");
  const DracoPointCloud decoded = decode_draco_point_cloud(encoded.bytes);
  const ScalarField* ids = find_field(decoded.fields, "id");
  ASSERT_NE(ids, nullptr);
  double max_error = 0;
  for (size_t k = 0; k < decoded.positions.size(); ++k) {
    const auto i = static_cast<size_t>(ids->values[k]);
    ASSERT_LT(i, points.size());
    max_error =
        std::max<double>(max_error, (decoded.positions[k] - points[i]).cast<double>().norm());
  }
  EXPECT_NEAR(encoded.max_position_error_m, max_error, 1e-9);
}

TEST(DracoCodec, QuantizedFieldsStayWithinTheirStep) {
  constexpr size_t kPoints = 2000;
  const auto points = random_points(kPoints, 5);
  ScalarField deviation{"deviation", {}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  for (size_t i = 0; i < kPoints; ++i) deviation.values.push_back(u(rng));
  DracoOptions options;
  options.field_bits = 12;  // ids 0..1999 keep |error| <= 1999 / 4095 / 2 < 0.5
  const DracoEncoded encoded =
      encode_draco_point_cloud(points, {id_field(kPoints), deviation}, options);
  const DracoPointCloud decoded = decode_draco_point_cloud(encoded.bytes);
  const ScalarField* ids = find_field(decoded.fields, "id");
  const ScalarField* dev = find_field(decoded.fields, "deviation");
  ASSERT_TRUE(ids != nullptr && dev != nullptr);
  for (size_t k = 0; k < kPoints; ++k) {
    const auto i = static_cast<size_t>(std::lround(ids->values[k]));
    ASSERT_LT(i, kPoints);
    EXPECT_LE(std::abs(dev->values[k] - deviation.values[i]), 1.0 / 4095 * 0.5 + 1e-6);
  }
}

TEST(DracoCodec, PointCloudIntensityBecomesAField) {
  PointCloud cloud;
  cloud.xyz = random_points(100, 1);
  for (int i = 0; i < 100; ++i) cloud.intensity.push_back(static_cast<float>(i));
  DracoOptions options;
  options.field_bits = 0;
  const DracoPointCloud decoded =
      decode_draco_point_cloud(encode_draco_point_cloud(cloud, {}, options).bytes);
  const ScalarField* intensity = find_field(decoded.fields, "intensity");
  ASSERT_NE(intensity, nullptr);
  EXPECT_EQ(std::multiset<float>(intensity->values.begin(), intensity->values.end()),
            std::multiset<float>(cloud.intensity.begin(), cloud.intensity.end()));
}

// A combined map encoded from its parts must be the file of the concatenated cloud (built here
// by hand), byte for byte, with the same error figures; intensity is kept only when every
// non-empty part has it.
TEST(DracoCodec, PartsEncodeAsTheirConcatenation) {
  PointCloud a, empty, b;
  a.xyz = random_points(700, 3);
  b.xyz = random_points(300, 4);
  for (auto& p : b.xyz) p += Eigen::Vector3f(30.f, -8.f, 2.f);  // widens the quantization range
  for (size_t i = 0; i < a.size(); ++i) a.intensity.push_back(static_cast<float>(i % 200));
  for (size_t i = 0; i < b.size(); ++i) b.intensity.push_back(static_cast<float>(i % 50));
  PointCloud concatenated;
  concatenated.xyz = a.xyz;
  concatenated.xyz.insert(concatenated.xyz.end(), b.xyz.begin(), b.xyz.end());
  concatenated.intensity = a.intensity;
  concatenated.intensity.insert(concatenated.intensity.end(), b.intensity.begin(),
                                b.intensity.end());
  DracoOptions options;
  options.position_bits = 16;
  const DracoEncoded whole = encode_draco_point_cloud(concatenated, {}, options);
  const DracoEncoded parts = encode_draco_point_cloud({&a, &empty, &b}, options);
  EXPECT_EQ(parts.bytes, whole.bytes);
  EXPECT_EQ(parts.max_position_error_m, whole.max_position_error_m);
  EXPECT_EQ(parts.position_range_m, whole.position_range_m);
  EXPECT_EQ(parts.position_error_bound_m, whole.position_error_bound_m);
  EXPECT_EQ(parts.error_method, "replica");
  EXPECT_GT(parts.max_position_error_m, 0.0);
  EXPECT_LE(parts.max_position_error_m, parts.position_error_bound_m);
  DracoEncoded two_steps = encode_draco_point_cloud_bytes({&a, &empty, &b}, options);
  EXPECT_EQ(two_steps.bytes, whole.bytes);
  EXPECT_EQ(two_steps.max_position_error_m, 0.0);  // not measured yet
  measure_draco_point_cloud({&a, &empty, &b}, options, &two_steps);
  EXPECT_EQ(two_steps.max_position_error_m, whole.max_position_error_m);
  EXPECT_EQ(two_steps.position_error_bound_m, whole.position_error_bound_m);
  EXPECT_EQ(two_steps.error_method, "replica");
  DracoEncoded truncated = encode_draco_point_cloud_bytes({&a, &b}, options);
  truncated.bytes.resize(truncated.bytes.size() / 2);
  EXPECT_THROW(measure_draco_point_cloud({&a, &b}, options, &truncated), std::runtime_error);

  b.intensity.clear();  // one part without intensity: the union carries none
  const DracoEncoded without = encode_draco_point_cloud({&a, &b}, options);
  EXPECT_EQ(without.bytes, encode_draco_point_cloud(concatenated.xyz, {}, options).bytes);
  EXPECT_EQ(find_field(decode_draco_point_cloud(without.bytes).fields, "intensity"), nullptr);

  EXPECT_THROW(encode_draco_point_cloud({&empty}, options), std::invalid_argument);
  a.intensity.pop_back();
  EXPECT_THROW(encode_draco_point_cloud({&a, &b}, options), std::invalid_argument);
}

TEST(DracoCodec, MeshRoundTripKeepsTopologyAndBoundsError) {
  const TriangleMesh mesh = testing::make_icosphere(3, 4.0, {1, 2, 3});  // 642 vertices
  const size_t n = mesh.vertices.size();
  ScalarField deviation{"deviation", {}};
  for (const auto& v : mesh.vertices) deviation.values.push_back(static_cast<float>(0.1 * v.x()));
  for (const int bits : {10, 14}) {
    SCOPED_TRACE("position_bits " + std::to_string(bits));
    DracoOptions options;
    options.position_bits = bits;
    options.field_bits = 0;
    const DracoEncoded encoded = encode_draco_mesh(mesh, {id_field(n), deviation}, options);
    const DracoMesh decoded = decode_draco_mesh(encoded.bytes);
    ASSERT_EQ(decoded.mesh.faces.size(), mesh.faces.size());
    const ScalarField* ids = find_field(decoded.fields, "id");
    const ScalarField* dev = find_field(decoded.fields, "deviation");
    ASSERT_TRUE(ids != nullptr && dev != nullptr);
    // Map decoded vertices to original ones and compare errors and faces.
    std::vector<int> original(decoded.mesh.vertices.size());
    double max_error = 0;
    for (size_t k = 0; k < decoded.mesh.vertices.size(); ++k) {
      original[k] = static_cast<int>(ids->values[k]);
      ASSERT_TRUE(original[k] >= 0 && original[k] < static_cast<int>(n));
      max_error =
          std::max(max_error, (decoded.mesh.vertices[k] - mesh.vertices[original[k]]).norm());
      EXPECT_EQ(dev->values[k], deviation.values[original[k]]);
    }
    TriangleMesh remapped = mesh;
    remapped.faces.clear();
    for (const auto& f : decoded.mesh.faces) {
      remapped.faces.emplace_back(original[f[0]], original[f[1]], original[f[2]]);
    }
    EXPECT_EQ(testing::canonical_triangles(remapped), testing::canonical_triangles(mesh));
    EXPECT_NEAR(encoded.position_range_m, 8.0, 1e-3);
    EXPECT_LE(max_error, 8.0 / std::pow(2.0, bits));
    EXPECT_NEAR(encoded.max_position_error_m, max_error, 1e-6);
  }
}

TEST(DracoCodec, RejectsBadInput) {
  const auto points = random_points(10, 2);
  DracoOptions bad;
  bad.position_bits = 31;
  EXPECT_THROW(encode_draco_point_cloud(points, {}, bad), std::invalid_argument);
  bad = DracoOptions();
  bad.compression_level = 11;
  EXPECT_THROW(encode_draco_point_cloud(points, {}, bad), std::invalid_argument);
  EXPECT_THROW(encode_draco_point_cloud(std::vector<Eigen::Vector3f>{}), std::invalid_argument);
  auto with_nan = points;
  with_nan[4].y() = std::nanf("");
  EXPECT_THROW(encode_draco_point_cloud(with_nan), std::invalid_argument);
  EXPECT_THROW(encode_draco_point_cloud(points, {{"density", {1.f}}}), std::invalid_argument);
  TriangleMesh no_faces;
  no_faces.vertices = {Eigen::Vector3d::Zero()};
  EXPECT_THROW(encode_draco_mesh(no_faces), std::invalid_argument);
  EXPECT_THROW(decode_draco_point_cloud("not a draco file", "x.drc"), std::runtime_error);
  const std::string cloud_bytes = encode_draco_point_cloud(points).bytes;
  EXPECT_THROW(decode_draco_mesh(cloud_bytes, "x.drc"), std::runtime_error);
  EXPECT_THROW(decode_draco_point_cloud(cloud_bytes.substr(0, cloud_bytes.size() / 2), "x.drc"),
               std::runtime_error);
}

// Element count from a PLY header, e.g. ply_count(text, "vertex").
long ply_count(const std::string& text, const std::string& element) {
  const std::string key = "element " + element + " ";
  const size_t at = text.find(key);
  return at == std::string::npos ? -1 : std::stol(text.substr(at + key.size()));
}

TEST(DracoCodec, FilesDecodeWithDracoDecoderCli) {
  if (std::system("command -v draco_decoder > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "draco_decoder not installed (Debian package 'draco')";
  }
  const auto dir = testing::scratch_dir();
  const auto points = random_points(500, 9);
  write_draco_file(dir / "map.drc", encode_draco_point_cloud(points, {id_field(500)}).bytes);
  const TriangleMesh mesh = testing::make_icosphere(2);
  write_draco_file(dir / "hull.drc", encode_draco_mesh(mesh).bytes);
  for (const std::string name : {"map", "hull"}) {
    const std::string command = "draco_decoder -i " + (dir / (name + ".drc")).string() + " -o " +
                                (dir / (name + ".ply")).string() + " > " +
                                (dir / (name + ".log")).string() + " 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
  }
  std::ifstream map_in(dir / "map.ply", std::ios::binary),
      hull_in(dir / "hull.ply", std::ios::binary);
  const std::string map_ply((std::istreambuf_iterator<char>(map_in)), {});
  const std::string hull_ply((std::istreambuf_iterator<char>(hull_in)), {});
  EXPECT_EQ(ply_count(map_ply, "vertex"), 500);
  EXPECT_EQ(ply_count(hull_ply, "vertex"), static_cast<long>(mesh.vertices.size()));
  EXPECT_EQ(ply_count(hull_ply, "face"), static_cast<long>(mesh.faces.size()));
  EXPECT_EQ(read_draco_file(dir / "hull.drc"), encode_draco_mesh(mesh).bytes);
}

// A cloud written by another tool with a float64 field: values within float's range are read
// (rounded to float), a value beyond it is an error naming the file, the field and the point,
// rather than the undefined double-to-float conversion Draco's ConvertValue<float> would do.
std::string cloud_with_float64_field(const std::vector<double>& values) {
  draco::PointCloud cloud;
  cloud.set_num_points(static_cast<draco::PointIndex::ValueType>(values.size()));
  draco::GeometryAttribute position;
  position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false,
                3 * sizeof(float), 0);
  const int position_id = cloud.AddAttribute(position, true, values.size());
  draco::GeometryAttribute field;
  field.Init(draco::GeometryAttribute::GENERIC, nullptr, 1, draco::DT_FLOAT64, false,
             sizeof(double), 0);
  const int field_id = cloud.AddAttribute(field, true, values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    const float xyz[3] = {static_cast<float>(i), 0.5f, -1.0f};
    cloud.attribute(position_id)->SetAttributeValue(draco::AttributeValueIndex(i), xyz);
    cloud.attribute(field_id)->SetAttributeValue(draco::AttributeValueIndex(i), &values[i]);
  }
  draco::Encoder encoder;
  encoder.SetSpeedOptions(10, 10);  // sequential, no quantization: the doubles are stored as is
  encoder.SetEncodingMethod(draco::POINT_CLOUD_SEQUENTIAL_ENCODING);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodePointCloudToBuffer(cloud, &buffer);
  EXPECT_TRUE(status.ok()) << status.error_msg_string();
  return std::string(buffer.data(), buffer.size());
}

TEST(DracoCodec, Float64FieldsReadAsFloatAndOutOfRangeValuesAreRefused) {
  const std::vector<double> in_range = {0.0, -2.25, 1e30, 3.0e38};
  const DracoPointCloud decoded =
      decode_draco_point_cloud(cloud_with_float64_field(in_range), "survey.drc");
  ASSERT_EQ(decoded.positions.size(), in_range.size());
  const ScalarField* field = find_field(decoded.fields, "generic_1");
  ASSERT_NE(field, nullptr);
  ASSERT_EQ(field->values.size(), in_range.size());
  for (size_t i = 0; i < in_range.size(); ++i)
    EXPECT_EQ(field->values[i], static_cast<float>(in_range[i])) << i;

  const std::string beyond = cloud_with_float64_field({1.0, 2.0, 1e300});
  try {
    (void)decode_draco_point_cloud(beyond, "survey.drc");
    FAIL() << "a float64 value of 1e300 was read as a float";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("survey.drc"), std::string::npos) << message;
    EXPECT_NE(message.find("'generic_1' value 2"), std::string::npos) << message;
  }
}

// fuzz_draco's input: a mesh whose 'deviation' attribute was turned into a bool holding bytes
// other than 0 and 1. Draco's ConvertValue<float> loads them as bool (undefined behaviour, which
// the sanitizer build reports); Keel reads each as 0 or 1.
TEST(DracoCodec, ABoolAttributeHoldingOtherBytesReadsAsZeroOrOne) {
  std::ifstream in(
      std::string(KEEL_SOURCE_DIR) + "/tests/fuzz/regressions/draco/bool-attribute-byte-35",
      std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1u);
  bytes.erase(0, 1);  // the harness's selector byte
  const DracoMesh decoded = decode_draco_mesh(bytes, "hull.drc");
  const ScalarField* flag = find_field(decoded.fields, "deviation");
  ASSERT_NE(flag, nullptr);
  ASSERT_FALSE(flag->values.empty());
  for (float v : flag->values) EXPECT_TRUE(v == 0.0f || v == 1.0f) << v;
}

}  // namespace
}  // namespace keel::io
