// write_ply_mesh and write_ply_cloud, read back with Keel's reader and, as an independent
// oracle, with PCL's PLY reader (what "tools without Draco" would use).
#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/PolygonMesh.h>
#include <pcl/io/ply_io.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

#include "tests/core/mesh_fixtures.h"
#include "tests/worker/io/mesh_test_util.h"
#include "worker/io/mesh/mesh_ply_writer.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/cloud/ply_cloud_writer.h"

namespace keel::io {
namespace {

// Value of float field `name` for point i of a PCL cloud; fails the test if absent.
float pcl_float(const pcl::PCLPointCloud2& cloud, const std::string& name, size_t i) {
  for (const auto& field : cloud.fields) {
    if (field.name != name) continue;
    EXPECT_EQ(field.datatype, pcl::PCLPointField::FLOAT32) << name;
    float value = 0;
    std::memcpy(&value, &cloud.data[i * cloud.point_step + field.offset], sizeof(float));
    return value;
  }
  ADD_FAILURE() << "field " << name << " missing";
  return 0;
}

TEST(PlyMeshWriter, RoundTripsGeometryAndDeviationField) {
  const TriangleMesh mesh = testing::make_icosphere(2, 3.0, {10, -4, 2});
  ScalarField deviation{"deviation", {}};
  for (const auto& v : mesh.vertices) deviation.values.push_back(static_cast<float>(v.z() * 0.01));
  const auto path = testing::scratch_dir() / "hull.ply";
  write_ply_mesh(path, mesh, {deviation});

  const TriangleMesh read = read_ply_mesh(path);
  ASSERT_EQ(read.vertices.size(), mesh.vertices.size());
  ASSERT_EQ(read.faces, mesh.faces);
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    EXPECT_LT((read.vertices[i] - mesh.vertices[i]).norm(), 1e-5);  // float32 positions
  }

  pcl::PolygonMesh pcl_mesh;
  ASSERT_EQ(pcl::io::loadPLYFile(path.string(), pcl_mesh), 0);
  ASSERT_EQ(pcl_mesh.polygons.size(), mesh.faces.size());
  ASSERT_EQ(pcl_mesh.cloud.width * pcl_mesh.cloud.height, mesh.vertices.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    ASSERT_EQ(pcl_mesh.polygons[f].vertices.size(), 3u);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(static_cast<int>(pcl_mesh.polygons[f].vertices[c]), mesh.faces[f][c]);
    }
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    EXPECT_FLOAT_EQ(pcl_float(pcl_mesh.cloud, "deviation", i), deviation.values[i]);
    EXPECT_FLOAT_EQ(pcl_float(pcl_mesh.cloud, "x", i), static_cast<float>(mesh.vertices[i].x()));
  }
}

TEST(PlyMeshWriter, DoublePositionsNormalsAndColors) {
  TriangleMesh mesh = testing::make_box({500000.125, 6000000.25, -3}, {500010.5, 6000002, 1});
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    mesh.vertex_normals.push_back(mesh.vertices[i].normalized());
    mesh.vertex_colors.emplace_back(static_cast<uint8_t>(i), 200, 7);
  }
  const auto path = testing::scratch_dir() / "utm.ply";
  PlyMeshWriteOptions options;
  options.double_positions = true;
  write_ply_mesh(path, mesh, {}, options);
  const TriangleMesh read = read_ply_mesh(path);
  EXPECT_EQ(read.vertices, mesh.vertices);  // exact: UTM coordinates need doubles
  ASSERT_EQ(read.vertex_colors.size(), mesh.vertices.size());
  EXPECT_EQ(read.vertex_colors[5], (Eigen::Matrix<uint8_t, 3, 1>(5, 200, 7)));
  ASSERT_EQ(read.vertex_normals.size(), mesh.vertices.size());
  EXPECT_LT((read.vertex_normals[3] - mesh.vertex_normals[3]).norm(), 1e-6);
}

TEST(PlyMeshWriter, RejectsBadFieldsAndLeavesNoFile) {
  const TriangleMesh mesh = testing::make_box({0, 0, 0}, {1, 1, 1});
  const auto dir = testing::scratch_dir();
  EXPECT_THROW(write_ply_mesh(dir / "a.ply", mesh, {{"deviation", {1.f, 2.f}}}),
               std::invalid_argument);
  EXPECT_THROW(write_ply_mesh(dir / "b.ply", mesh, {{"bad name", std::vector<float>(8)}}),
               std::invalid_argument);
  EXPECT_THROW(write_ply_mesh(dir / "c.ply", mesh, {{"x", std::vector<float>(8)}}),
               std::invalid_argument);
  EXPECT_THROW(write_ply_mesh(dir / "missing_dir" / "d.ply", mesh), std::runtime_error);
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

TEST(PlyCloudWriter, FieldsReadBackWithPcl) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-50.f, 50.f);
  PointCloud cloud;
  ScalarField density{"density", {}};
  ScalarField deviation{"deviation", {}};
  for (int i = 0; i < 1000; ++i) {
    cloud.xyz.emplace_back(u(rng), u(rng), u(rng));
    cloud.intensity.push_back(static_cast<float>(i % 256));
    density.values.push_back(u(rng));
    deviation.values.push_back(0.001f * i);
  }
  const auto path = testing::scratch_dir() / "map.ply";
  write_ply_cloud(path, cloud, {density, deviation});

  pcl::PCLPointCloud2 read;
  ASSERT_EQ(pcl::io::loadPLYFile(path.string(), read), 0);
  ASSERT_EQ(read.width * read.height, cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_EQ(pcl_float(read, "x", i), cloud.xyz[i].x());
    EXPECT_EQ(pcl_float(read, "y", i), cloud.xyz[i].y());
    EXPECT_EQ(pcl_float(read, "z", i), cloud.xyz[i].z());
    EXPECT_EQ(pcl_float(read, "intensity", i), cloud.intensity[i]);
    EXPECT_EQ(pcl_float(read, "density", i), density.values[i]);
    EXPECT_EQ(pcl_float(read, "deviation", i), deviation.values[i]);
  }
}

std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A combined map written from its parts must be the PLY of the concatenated cloud (built here
// by hand), byte for byte; the first part spans more than one streamed chunk (65536 points).
TEST(PlyCloudWriter, PartsWriteTheirConcatenation) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-50.f, 50.f);
  PointCloud a, empty, b;
  for (int i = 0; i < 70001; ++i) {
    a.xyz.emplace_back(u(rng), u(rng), u(rng));
    a.intensity.push_back(u(rng));
  }
  for (int i = 0; i < 123; ++i) {
    b.xyz.emplace_back(u(rng), u(rng), u(rng));
    b.intensity.push_back(u(rng));
  }
  PointCloud concatenated = a;
  concatenated.xyz.insert(concatenated.xyz.end(), b.xyz.begin(), b.xyz.end());
  concatenated.intensity.insert(concatenated.intensity.end(), b.intensity.begin(),
                                b.intensity.end());
  const auto dir = testing::scratch_dir();
  write_ply_cloud(dir / "whole.ply", concatenated);
  write_ply_cloud(dir / "parts.ply", std::vector<const PointCloud*>{&a, &empty, &b});
  const std::string whole = file_bytes(dir / "whole.ply");
  EXPECT_EQ(whole.size(), 16 * concatenated.size() + whole.find("end_header\n") + 11);
  EXPECT_EQ(file_bytes(dir / "parts.ply"), whole);

  b.intensity.clear();  // one part without intensity: the union carries none
  concatenated.intensity.clear();
  write_ply_cloud(dir / "whole_xyz.ply", concatenated);
  write_ply_cloud(dir / "parts_xyz.ply", std::vector<const PointCloud*>{&a, &b});
  EXPECT_EQ(file_bytes(dir / "parts_xyz.ply"), file_bytes(dir / "whole_xyz.ply"));

  a.intensity.pop_back();  // a bad part: nothing written, not even a partial file
  EXPECT_THROW(write_ply_cloud(dir / "bad.ply", std::vector<const PointCloud*>{&a}),
               std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.ply"));
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.ply.partial"));
}

TEST(PlyCloudWriter, RejectsMismatchedSizes) {
  PointCloud cloud;
  cloud.xyz.resize(3, Eigen::Vector3f::Zero());
  cloud.intensity.resize(2);
  const auto dir = testing::scratch_dir();
  EXPECT_THROW(write_ply_cloud(dir / "a.ply", cloud), std::invalid_argument);
  cloud.intensity.clear();
  EXPECT_THROW(write_ply_cloud(dir / "b.ply", cloud, {{"density", {1.f}}}), std::invalid_argument);
  const ScalarField twice{"twice", {1.f, 2.f, 3.f}};
  EXPECT_THROW(write_ply_cloud(dir / "c.ply", cloud, {twice, twice}), std::invalid_argument);
  EXPECT_THROW(write_ply_cloud(dir / "d.ply", cloud, {{"intensity", {1.f, 2.f, 3.f}}}),
               std::invalid_argument);
}

}  // namespace
}  // namespace keel::io
