// 2.5D alpha shapes (Algorithm 1, line 13, seed 001) on point sets with known shapes.
#include "worker/inspect/alpha_shape_25d.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>

namespace keel::inspect {
namespace {

double triangle_area_xy(const TriangleMesh& m, const Eigen::Vector3i& f) {
  const Eigen::Vector2d a = m.vertices[f[0]].head<2>(), b = m.vertices[f[1]].head<2>(),
                        c = m.vertices[f[2]].head<2>();
  const Eigen::Vector2d u = b - a, v = c - a;
  return 0.5 * std::abs(u.x() * v.y() - u.y() * v.x());
}

double area_xy(const TriangleMesh& m) {
  double area = 0.0;
  for (const auto& f : m.faces) area += triangle_area_xy(m, f);
  return area;
}

bool covers_xy(const TriangleMesh& m, const Eigen::Vector2d& p) {
  for (const auto& f : m.faces) {
    const Eigen::Vector2d a = m.vertices[f[0]].head<2>(), b = m.vertices[f[1]].head<2>(),
                          c = m.vertices[f[2]].head<2>();
    auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
      return u.x() * v.y() - u.y() * v.x();
    };
    const double d1 = cross(b - a, p - a), d2 = cross(c - b, p - b), d3 = cross(a - c, p - c);
    if ((d1 >= 0 && d2 >= 0 && d3 >= 0) || (d1 <= 0 && d2 <= 0 && d3 <= 0)) return true;
  }
  return false;
}

// Edges used by exactly one face.
std::vector<std::pair<int, int>> boundary_edges(const TriangleMesh& m) {
  std::map<std::pair<int, int>, int> uses;
  for (const auto& f : m.faces) {
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(f[k], f[(k + 1) % 3])];
  }
  std::vector<std::pair<int, int>> out;
  for (const auto& [edge, n] : uses) {
    if (n == 1) out.push_back(edge);
  }
  return out;
}

int num_components(const TriangleMesh& m) {
  std::vector<int> parent(m.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const auto& f : m.faces) {
    parent[find(f[1])] = find(f[0]);
    parent[find(f[2])] = find(f[0]);
  }
  int n = 0;
  for (size_t i = 0; i < parent.size(); ++i) n += find(static_cast<int>(i)) == static_cast<int>(i);
  return n;
}

// Points of a grid with `step` inside `inside`, plus extra points; z from `height`.
template <typename Inside, typename Height>
std::vector<Eigen::Vector3d> grid_points(double lo, double hi, double step, Inside inside,
                                         Height height) {
  std::vector<Eigen::Vector3d> points;
  const int n = static_cast<int>(std::lround((hi - lo) / step));
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double x = lo + i * step, y = lo + j * step;
      if (inside(x, y)) points.emplace_back(x, y, height(x, y));
    }
  }
  return points;
}

TEST(AlphaShape25d, DiskBoundaryFollowsTheCircleAndKeepsHeights) {
  const double radius = 0.1;
  auto height = [](double x, double y) { return 1.4 + 0.3 * x - 0.2 * y; };
  auto points = grid_points(
      -0.1, 0.1, 0.01, [&](double x, double y) { return std::hypot(x, y) < radius - 0.005; },
      height);
  for (int k = 0; k < 64; ++k) {
    const double phi = 2.0 * M_PI * k / 64;
    const double x = radius * std::cos(phi), y = radius * std::sin(phi);
    points.emplace_back(x, y, height(x, y));
  }
  const Shape25d shape = alpha_shape_25d(points, 0.12);
  ASSERT_FALSE(shape.mesh.faces.empty());
  // The 64-gon inscribed in the circle: area 0.5 * 64 * r^2 * sin(2 pi / 64).
  const double polygon_area = 0.5 * 64 * radius * radius * std::sin(2.0 * M_PI / 64);
  EXPECT_NEAR(area_xy(shape.mesh), polygon_area, 1e-9);
  const auto boundary = boundary_edges(shape.mesh);
  EXPECT_EQ(boundary.size(), 64u);
  for (const auto& [a, b] : boundary) {
    EXPECT_NEAR(shape.mesh.vertices[a].head<2>().norm(), radius, 1e-9);
    EXPECT_NEAR(shape.mesh.vertices[b].head<2>().norm(), radius, 1e-9);
  }
  ASSERT_EQ(shape.source_index.size(), shape.mesh.vertices.size());
  for (size_t k = 0; k < shape.mesh.vertices.size(); ++k) {
    EXPECT_EQ(shape.mesh.vertices[k], points[shape.source_index[k]]);  // 2.5D: z kept
  }
  // Normals face the camera at the origin (-z side).
  for (const auto& f : shape.mesh.faces) {
    const Eigen::Vector3d n = (shape.mesh.vertices[f[1]] - shape.mesh.vertices[f[0]])
                                  .cross(shape.mesh.vertices[f[2]] - shape.mesh.vertices[f[0]]);
    EXPECT_LT(n.z(), 0.0);
  }
}

TEST(AlphaShape25d, TwoClustersFarApartGiveTwoComponents) {
  auto flat = [](double, double) { return 1.5; };
  auto square = [](double, double) { return true; };
  auto points = grid_points(-0.1, 0.1, 0.025, square, flat);
  const size_t first = points.size();
  for (size_t k = 0; k < first; ++k) points.push_back(points[k] + Eigen::Vector3d(1.0, 0, 0));
  const Shape25d shape = alpha_shape_25d(points, 0.12);
  EXPECT_EQ(num_components(shape.mesh), 2);
  EXPECT_NEAR(area_xy(shape.mesh), 2 * 0.2 * 0.2, 1e-9);
  EXPECT_FALSE(covers_xy(shape.mesh, {0.5, 0.0}));
}

TEST(AlphaShape25d, SmallAlphaKeepsTheConcavityOfAnL) {
  auto flat = [](double, double) { return 1.5; };
  auto l_shape = [](double x, double y) {
    return (y <= 0.1 + 1e-9 && x <= 0.4 + 1e-9) || (x <= 0.1 + 1e-9 && y <= 0.4 + 1e-9);
  };
  const auto points = grid_points(0.0, 0.4, 0.02, l_shape, flat);
  const double l_area = 0.4 * 0.1 + 0.1 * 0.3;
  const double hull_area = 0.4 * 0.4 - 0.5 * 0.3 * 0.3;
  const Shape25d small = alpha_shape_25d(points, 0.03);
  // The L, plus at most a few triangles bridging the inner corner (circumradius <= 0.03 m).
  EXPECT_GE(area_xy(small.mesh), l_area - 1e-9);
  EXPECT_LE(area_xy(small.mesh), l_area + 0.002);
  EXPECT_FALSE(covers_xy(small.mesh, {0.2, 0.2}));  // inside the convex hull, outside the L
  EXPECT_FALSE(covers_xy(small.mesh, {0.3, 0.15}));
  EXPECT_TRUE(covers_xy(small.mesh, {0.05, 0.35}));
  EXPECT_TRUE(covers_xy(small.mesh, {0.35, 0.05}));
  // A huge alpha gives the convex hull, which fills the notch.
  const Shape25d hull = alpha_shape_25d(points, 100.0);
  EXPECT_NEAR(area_xy(hull.mesh), hull_area, 1e-9);
  EXPECT_TRUE(covers_xy(hull.mesh, {0.2, 0.2}));
}

TEST(AlphaShape25d, AlphaIsTheRadiusNotItsSquare) {
  // Equilateral triangle with circumradius 0.1 m: kept for alpha_m >= 0.1, dropped below.
  // Were alpha_m passed to CGAL unsquared, 0.099 (> 0.1^2) would keep it.
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < 3; ++k) {
    const double phi = 2.0 * M_PI * k / 3;
    points.emplace_back(0.1 * std::cos(phi), 0.1 * std::sin(phi), 1.0);
  }
  EXPECT_EQ(alpha_shape_25d(points, 0.101).mesh.faces.size(), 1u);
  EXPECT_TRUE(alpha_shape_25d(points, 0.099).mesh.faces.empty());
}

TEST(AlphaShape25d, DegenerateAndBadInput) {
  EXPECT_TRUE(alpha_shape_25d({{0, 0, 1}, {0.01, 0, 1}}, 0.12).mesh.faces.empty());
  EXPECT_TRUE(alpha_shape_25d({{0, 0, 1}, {0.01, 0, 1}, {0.02, 0, 1}}, 0.12).mesh.faces.empty());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(alpha_shape_25d({{0, 0, 1}, {nan, 0, 1}, {0, 0.01, 1}}, 0.12),
               std::invalid_argument);
  EXPECT_THROW(alpha_shape_25d({{0, 0, 1}}, -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace keel::inspect
