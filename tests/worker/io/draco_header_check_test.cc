// The counts read from a Draco header are the ones Keel's encoder wrote (each encoding method
// Draco chooses: sequential and kd-tree clouds, sequential and edgebreaker meshes); a header
// that declares more than the limits is refused before Draco allocates for it.
#include "worker/io/draco/draco_header_check.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>

#include "worker/io/draco/draco_codec.h"

namespace keel::io {
namespace {

constexpr size_t kMethodByte = 8;  // "DRACO", major, minor, geometry type, method, flags

std::vector<Eigen::Vector3f> spiral(size_t n) {
  std::vector<Eigen::Vector3f> points;
  for (size_t i = 0; i < n; ++i)
    points.emplace_back(std::cos(0.1 * i) * i * 0.01, std::sin(0.1 * i) * i * 0.01, 0.001 * i);
  return points;
}

// A side x side grid of vertices, two triangles a cell, on a wavy surface.
TriangleMesh grid(int side) {
  TriangleMesh mesh;
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c)
      mesh.vertices.emplace_back(c * 0.1, r * 0.1, 0.05 * std::sin(0.7 * c) * std::cos(0.3 * r));
  for (int r = 0; r + 1 < side; ++r)
    for (int c = 0; c + 1 < side; ++c) {
      const int v = side * r + c;
      mesh.faces.emplace_back(v, v + 1, v + side + 1);
      mesh.faces.emplace_back(v, v + side + 1, v + side);
    }
  return mesh;
}

DracoOptions level(int compression_level) {
  DracoOptions options;
  options.compression_level = compression_level;
  return options;
}

TEST(DracoHeaderCheck, ReadsTheCountsKeelsEncoderWroteForEachMethod) {
  const auto points = spiral(5000);
  for (int compression : {0, 7}) {
    const std::string bytes = encode_draco_point_cloud(points, {}, level(compression)).bytes;
    const auto counts = read_draco_counts(bytes);
    ASSERT_TRUE(counts);
    EXPECT_FALSE(counts->mesh);
    EXPECT_EQ(counts->points, points.size());
    EXPECT_EQ(bytes[kMethodByte], compression == 0 ? 0 : 1);  // sequential, kd-tree
  }
  const TriangleMesh mesh = grid(40);
  const std::vector<ScalarField> fields = {{"deviation", std::vector<float>(1600, 0.5f)}};
  for (int compression : {0, 7}) {
    const std::string bytes = encode_draco_mesh(mesh, fields, level(compression)).bytes;
    const auto counts = read_draco_counts(bytes);  // the name metadata comes first
    ASSERT_TRUE(counts);
    EXPECT_TRUE(counts->mesh);
    EXPECT_EQ(counts->points, mesh.vertices.size());
    EXPECT_EQ(counts->faces, mesh.faces.size());
    EXPECT_EQ(bytes[kMethodByte], compression == 0 ? 0 : 1);  // sequential, edgebreaker
    EXPECT_NO_THROW(check_draco_header(bytes, "hull.drc"));
  }
}

TEST(DracoHeaderCheck, NoBoundRelativeToTheFileSizeWouldBeSoundSoTheLimitIsAbsolute) {
  // A cloud of one point repeated, at the highest compression level: the kd-tree coder stores
  // it in a few hundred bytes, so a bound of points per byte would refuse a valid file.
  const std::vector<Eigen::Vector3f> same(200000, Eigen::Vector3f(1.f, 2.f, 3.f));
  const std::string bytes = encode_draco_point_cloud(same, {}, level(10)).bytes;
  EXPECT_GT(double(same.size()) / bytes.size(), 256.0) << bytes.size() << " bytes";
  EXPECT_NO_THROW(check_draco_header(bytes, "same.drc"));
  EXPECT_EQ(decode_draco_point_cloud(bytes, "same.drc").positions.size(), same.size());
  // The limit is the caller's.
  EXPECT_NO_THROW(check_draco_header(bytes, "same.drc", {200000, 0}));
  EXPECT_THROW(decode_draco_point_cloud(bytes, "same.drc", {199999, 0}), std::runtime_error);
  const TriangleMesh mesh = grid(40);
  const std::string mesh_bytes = encode_draco_mesh(mesh, {}, level(7)).bytes;
  const auto counts = read_draco_counts(mesh_bytes);  // edgebreaker: split vertices count too
  ASSERT_TRUE(counts);
  const uint64_t vertices = counts->points + counts->split_vertices;
  EXPECT_NO_THROW(decode_draco_mesh(mesh_bytes, "hull.drc", {vertices, mesh.faces.size()}));
  EXPECT_THROW(decode_draco_mesh(mesh_bytes, "hull.drc", {vertices - 1, mesh.faces.size()}),
               std::runtime_error);
  EXPECT_THROW(decode_draco_mesh(mesh_bytes, "hull.drc", {vertices, mesh.faces.size() - 1}),
               std::runtime_error);
}

TEST(DracoHeaderCheck, ACloudDeclaringMorePointsThanItsSizeHoldsIsRefusedBeforeDecoding) {
  const auto points = spiral(100);
  std::string bytes = encode_draco_point_cloud(points, {}, level(7)).bytes;
  // num_points, an int32 right after the 11-byte header (no metadata in this file).
  int32_t declared = 0;
  std::memcpy(&declared, bytes.data() + 11, 4);
  ASSERT_EQ(declared, 100);
  declared = 400000000;  // 4.8 GB of float positions: fuzz_draco's first find was this
  std::memcpy(bytes.data() + 11, &declared, 4);
  try {
    decode_draco_point_cloud(bytes, "map_0.drc");
    FAIL() << "decoded";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("map_0.drc"), std::string::npos) << message;
    EXPECT_NE(message.find("declares 400000000 points"), std::string::npos) << message;
  }
}

std::string varint(uint32_t v) {
  std::string out;
  do {
    out += static_cast<char>((v & 0x7f) | (v > 0x7f ? 0x80 : 0));
    v >>= 7;
  } while (v);
  return out;
}

TEST(DracoHeaderCheck, EdgebreakerAndSequentialMeshCountsAreBoundedToo) {
  // Headers written by hand from the bitstream layout (version 2.2, no metadata).
  const std::string head = std::string("DRACO") + '\x02' + '\x02' + '\x01';
  const std::string edgebreaker = head + '\x01' + std::string(2, '\0') + '\x00' /*traversal*/ +
                                  varint(3) + varint(500000000) /*faces*/ + '\x00' + varint(1) +
                                  varint(0) + std::string(64, '\0');
  auto counts = read_draco_counts(edgebreaker);
  ASSERT_TRUE(counts);
  EXPECT_EQ(counts->points, 3u);
  EXPECT_EQ(counts->faces, 500000000u);
  EXPECT_THROW(decode_draco_mesh(edgebreaker, "hull.drc"), std::runtime_error);
  try {
    check_draco_header(edgebreaker, "hull.drc");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("hull.drc: the Draco header declares 500000000 faces"),
              std::string::npos)
        << e.what();
  }
  const std::string sequential =
      head + '\x00' + std::string(2, '\0') + varint(1) + varint(300000000) /*points*/ + '\x00';
  counts = read_draco_counts(sequential);
  ASSERT_TRUE(counts);
  EXPECT_EQ(counts->points, 300000000u);
  EXPECT_THROW(check_draco_header(sequential, "hull.drc"), std::runtime_error);
}

TEST(DracoHeaderCheck, OnlyTheBitstreamsDracoWritesTodayAreRead) {
  // fuzz_draco's input: a kd-tree cloud of bitstream 2.2, whose attribute data (read by Draco's
  // backwards-compatibility path) declares its points again.
  std::ifstream in(
      std::string(KEEL_SOURCE_DIR) + "/tests/fuzz/regressions/draco/kd-tree-2.2-points-again-3.4GB",
      std::ios::binary);
  std::string old((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(old.size(), 1u);
  old.erase(0, 1);  // the harness's selector byte
  try {
    decode_draco_point_cloud(old, "map_0.drc");
    FAIL() << "decoded";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "map_0.drc: Draco bitstream 2.2; Keel reads point clouds of bitstream 2.3 "
              "(re-encode with a current draco_encoder)");
  }
  // What Keel writes passes: point clouds 2.3, meshes 2.2.
  const std::string cloud = encode_draco_point_cloud(spiral(10), {}, level(7)).bytes;
  EXPECT_EQ(cloud.substr(5, 2), std::string("\x02\x03"));
  EXPECT_NO_THROW(check_draco_header(cloud, "map_0.drc"));
  const std::string mesh = encode_draco_mesh(grid(4), {}, level(7)).bytes;
  EXPECT_EQ(mesh.substr(5, 2), std::string("\x02\x02"));
  EXPECT_NO_THROW(check_draco_header(mesh, "hull.drc"));
}

TEST(DracoHeaderCheck, WhatDracoRefusesItselfIsLeftToIt) {
  EXPECT_FALSE(read_draco_counts(""));
  EXPECT_FALSE(read_draco_counts("PLY\nnot draco"));
  EXPECT_FALSE(read_draco_counts(std::string("DRACO") + '\x09' + '\x00' + '\x00' + '\x00' +
                                 std::string(6, '\0')));  // unknown major version
  EXPECT_FALSE(read_draco_counts(std::string("DRACO\x02\x02\x00\x00", 9)));  // cut short
  EXPECT_THROW(decode_draco_point_cloud("PLY\nnot draco", "a.drc"), std::runtime_error);
}

}  // namespace
}  // namespace keel::io
