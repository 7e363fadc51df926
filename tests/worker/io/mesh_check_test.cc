#include "worker/io/mesh/mesh_check.h"

#include <gtest/gtest.h>

#include "tests/core/mesh_fixtures.h"

namespace keel::io {
namespace {

size_t warning_count(const MeshCheckReport& report, const std::string& kind) {
  size_t count = 0;
  for (const auto& w : report.warnings) {
    if (w.kind == kind) count += w.count;
  }
  return count;
}

TEST(MeshCheck, ClosedBoxIsClean) {
  const TriangleMesh box = testing::make_box({0, 0, 0}, {4, 2, 1});
  const MeshCheckReport report = check_mesh(box);
  EXPECT_TRUE(report.warnings.empty()) << report.to_json().dump(2);
  EXPECT_TRUE(report.is_closed());
  EXPECT_EQ(report.num_edges, 18u);  // Euler: V - E + F = 2 -> 8 - 18 + 12
  EXPECT_EQ(report.bbox_min, Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(report.bbox_max, Eigen::Vector3d(4, 2, 1));
  EXPECT_DOUBLE_EQ(report.largest_extent_m, 4.0);
}

TEST(MeshCheck, FindsPlantedNonManifoldEdgeAndDegenerateTriangles) {
  TriangleMesh mesh = testing::make_icosphere(1, 5.0);
  ASSERT_TRUE(check_mesh(mesh).warnings.empty());
  const int n = static_cast<int>(mesh.vertices.size());
  // A fin on an edge of the first face: that edge now has three faces.
  mesh.vertices.emplace_back(20, 0, 0);
  mesh.faces.emplace_back(mesh.faces[0][0], mesh.faces[0][1], n);
  // A repeated index, and a zero-area (collinear) triangle off to the side.
  mesh.faces.emplace_back(1, 1, 2);
  mesh.vertices.emplace_back(30, 0, 0);
  mesh.vertices.emplace_back(32, 0, 0);
  mesh.vertices.emplace_back(31, 0, 0);
  mesh.faces.emplace_back(n + 1, n + 2, n + 3);
  const MeshCheckReport report = check_mesh(mesh);
  EXPECT_EQ(report.non_manifold_edges, 1u);
  EXPECT_EQ(report.repeated_index_faces, 1u);
  EXPECT_EQ(report.zero_area_faces, 1u);
  EXPECT_EQ(report.degenerate_faces(), 2u);
  EXPECT_EQ(warning_count(report, "non_manifold_edges"), 1u);
  EXPECT_EQ(warning_count(report, "degenerate_faces"), 2u);
  // The fin's two other edges and the collinear face's three edges are boundary edges.
  EXPECT_EQ(report.boundary_edges, 5u);
  EXPECT_FALSE(report.is_closed());
}

TEST(MeshCheck, BoundaryDuplicatesOrientationAndUnusedVertices) {
  TriangleMesh mesh = testing::make_box({0, 0, 0}, {1, 1, 1});
  mesh.faces.erase(mesh.faces.begin());           // opens a hole: 3 boundary edges
  mesh.faces.push_back(mesh.faces.back());        // a duplicate face
  std::swap(mesh.faces[3][1], mesh.faces[3][2]);  // flips one face: its 3 edges disagree
  mesh.vertices.emplace_back(7, 7, 7);            // belongs to no face
  const MeshCheckReport report = check_mesh(mesh);
  EXPECT_EQ(report.boundary_edges, 3u);
  EXPECT_EQ(report.duplicate_faces, 1u);
  EXPECT_EQ(report.inconsistent_edges, 3u);
  EXPECT_EQ(report.unreferenced_vertices, 1u);
  EXPECT_EQ(report.non_manifold_edges, 0u);
}

TEST(MeshCheck, FlagsImplausibleUnits) {
  // A 100 km hull: probably millimetres read as metres.
  const MeshCheckReport huge = check_mesh(testing::make_uv_ellipsoid(16, 8, {1e5, 2e4, 1e4}));
  ASSERT_EQ(warning_count(huge, "units"), 1u);
  EXPECT_NE(huge.warnings.back().message.find("millimetres"), std::string::npos);
  // A 4 mm hull: probably kilometres.
  const MeshCheckReport tiny = check_mesh(testing::make_uv_ellipsoid(16, 8, {0.002, 0.001, 0.001}));
  ASSERT_EQ(warning_count(tiny, "units"), 1u);
  EXPECT_NE(tiny.warnings.back().message.find("kilometres"), std::string::npos);
  // A 60 m hull is plausible.
  EXPECT_EQ(warning_count(check_mesh(testing::make_uv_ellipsoid(16, 8, {30, 6, 4})), "units"), 0u);
}

TEST(MeshCheck, InvalidIndicesAreCountedNotFatal) {
  TriangleMesh mesh = testing::make_box({0, 0, 0}, {1, 1, 1});
  mesh.faces.emplace_back(0, 1, 99);
  const MeshCheckReport report = check_mesh(mesh);
  EXPECT_EQ(report.invalid_index_faces, 1u);
  EXPECT_EQ(warning_count(report, "invalid_indices"), 1u);
  EXPECT_EQ(report.to_json().at("invalid_index_faces"), 1);
}

}  // namespace
}  // namespace keel::io
