// MeshQuery against brute force over all triangles, and signs against the analytic solid.
#include "core/mesh_query.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <string>

#include "tests/core/mesh_fixtures.h"

namespace keel::ba {
namespace {

// Closest point on a triangle by a different route than the library's: project onto the
// plane; if the projection is inside use it, otherwise the best of the three edge segments.
Eigen::Vector3d brute_closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  const Eigen::Vector3d q = p - (p - a).dot(n) * n;
  const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                      (a - c).cross(q - c).dot(n) >= 0;
  if (inside) return q;
  Eigen::Vector3d best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const auto& [s, e] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
    const double t = std::clamp((p - s).dot(e - s) / (e - s).squaredNorm(), 0.0, 1.0);
    const Eigen::Vector3d x = s + t * (e - s);
    if ((p - x).norm() < best_distance) {
      best_distance = (p - x).norm();
      best = x;
    }
  }
  return best;
}

double brute_distance(const TriangleMesh& mesh, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d x =
        brute_closest_on_triangle(p, mesh.vertices[f[0]], mesh.vertices[f[1]], mesh.vertices[f[2]]);
    best = std::min(best, (p - x).norm());
  }
  return best;
}

// Moeller-Trumbore over all faces: nearest t in [0, max_range] (unit direction).
std::optional<std::pair<double, int>> brute_raycast(const TriangleMesh& mesh,
                                                    const Eigen::Vector3d& o,
                                                    const Eigen::Vector3d& d, double max_range) {
  std::optional<std::pair<double, int>> best;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3d& a = mesh.vertices[mesh.faces[f][0]];
    const Eigen::Vector3d e1 = mesh.vertices[mesh.faces[f][1]] - a;
    const Eigen::Vector3d e2 = mesh.vertices[mesh.faces[f][2]] - a;
    const Eigen::Vector3d h = d.cross(e2);
    const double det = e1.dot(h);
    if (std::abs(det) < 1e-14) continue;
    const Eigen::Vector3d s = o - a;
    const double u = s.dot(h) / det;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (u < 0 || v < 0 || u + v > 1) continue;
    const double t = e2.dot(q) / det;
    if (t < 0 || t > max_range) continue;
    if (!best || t < best->first) best = std::pair{t, static_cast<int>(f)};
  }
  return best;
}

struct Solid {
  std::string name;
  TriangleMesh mesh;
  std::function<bool(const Eigen::Vector3d&)> inside;
};

std::vector<Solid> solids() {
  std::vector<Solid> result;
  TriangleMesh sphere = testing::make_icosphere(2, 1.5, {0.3, -0.2, 0.1});
  result.push_back({"icosphere", sphere, [sphere](const Eigen::Vector3d& p) {
                      return testing::inside_convex(sphere, p);
                    }});
  TriangleMesh box = testing::make_box({-1, -0.5, 0}, {2, 0.5, 0.25});
  result.push_back(
      {"box", box, [box](const Eigen::Vector3d& p) { return testing::inside_convex(box, p); }});
  result.push_back({"l_prism", testing::make_l_prism(), testing::inside_l_prism});
  TriangleMesh wedge = testing::make_sharp_wedge();
  result.push_back({"sharp_wedge", wedge, [wedge](const Eigen::Vector3d& p) {
                      return testing::inside_convex(wedge, p);
                    }});
  return result;
}

// Uniform points around the mesh plus points close to its vertices and edges (where a
// plain face normal can give the wrong sign).
std::vector<Eigen::Vector3d> queries_near(const TriangleMesh& mesh, std::mt19937& rng, int n) {
  Eigen::Vector3d lo = mesh.vertices[0], hi = lo;
  for (const auto& v : mesh.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Eigen::Vector3d margin = 0.3 * (hi - lo);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> noise(0, 0.01);
  std::uniform_int_distribution<size_t> face(0, mesh.faces.size() - 1);
  std::vector<Eigen::Vector3d> queries;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d jitter(noise(rng), noise(rng), noise(rng));
    const auto& f = mesh.faces[face(rng)];
    const int c = static_cast<int>(rng() % 3);
    const Eigen::Vector3d& a = mesh.vertices[f[c]];
    const Eigen::Vector3d& b = mesh.vertices[f[(c + 1) % 3]];
    switch (i % 3) {
      case 0:
        queries.push_back(
            lo - margin +
            (hi - lo + 2 * margin).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng))));
        break;
      case 1:
        queries.push_back(a + jitter);
        break;
      default: {
        const double t = unit(rng);
        queries.push_back((1 - t) * a + t * b + jitter);
      }
    }
  }
  return queries;
}

TEST(MeshQuery, BoxClosedForms) {
  const MeshQuery query(testing::make_box({0, 0, 0}, {1, 1, 1}));
  const ClosestPoint above = query.closest_point({0.5, 0.25, 3});
  EXPECT_NEAR(above.signed_distance_m, 2.0, 1e-12);
  EXPECT_LT((above.point - Eigen::Vector3d(0.5, 0.25, 1)).norm(), 1e-12);
  EXPECT_EQ(above.feature, MeshFeature::kFace);
  EXPECT_LT((above.normal - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  EXPECT_NEAR(query.signed_distance({0.5, 0.5, 0.4}), -0.4, 1e-12);
  // Beyond a corner: the closest point is the vertex, the distance the diagonal.
  const ClosestPoint corner = query.closest_point({2, 2, 2});
  EXPECT_EQ(corner.feature, MeshFeature::kVertex);
  EXPECT_NEAR(corner.signed_distance_m, std::sqrt(3.0), 1e-12);
  EXPECT_LT((corner.normal - Eigen::Vector3d(1, 1, 1).normalized()).norm(), 1e-12);
  // Beyond an edge.
  const ClosestPoint edge = query.closest_point({2, 0.5, -1});
  EXPECT_EQ(edge.feature, MeshFeature::kEdge);
  EXPECT_NEAR(edge.signed_distance_m, std::sqrt(2.0), 1e-12);

  const auto hit = query.raycast({{0.5, 0.5, 5}, {0, 0, -2}, 100});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->distance_m, 4.0, 1e-12);
  EXPECT_LT((hit->point - Eigen::Vector3d(0.5, 0.5, 1)).norm(), 1e-12);
  EXPECT_LT((hit->face_normal - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  EXPECT_FALSE(query.raycast({{0.5, 0.5, 5}, {0, 0, -1}, 3.9}).has_value());
  EXPECT_FALSE(query.raycast({{0.5, 0.5, 5}, {0, 0, 1}, 100}).has_value());
  // Leaving the top face: min_range skips it and finds the bottom from inside.
  const auto through = query.raycast({{0.5, 0.5, 1}, {0, 0, -1}, 100, 1e-6});
  ASSERT_TRUE(through.has_value());
  EXPECT_NEAR(through->distance_m, 1.0, 1e-12);
  EXPECT_LT((through->face_normal + Eigen::Vector3d::UnitZ()).norm(), 1e-12);
}

TEST(MeshQuery, ClosestPointAndSignMatchBruteForceAndSolid) {
  std::mt19937 rng(42);
  for (const Solid& solid : solids()) {
    SCOPED_TRACE(solid.name);
    // The analytic solid agrees with the mesh's orientation.
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& v : solid.mesh.vertices) centroid += v / solid.mesh.vertices.size();
    ASSERT_TRUE(solid.inside(centroid) || solid.name == "l_prism");
    const MeshQuery query(solid.mesh);
    int on_edges = 0, on_vertices = 0, checked_signs = 0;
    for (const Eigen::Vector3d& p : queries_near(solid.mesh, rng, 3000)) {
      const ClosestPoint result = query.closest_point(p);
      const double expected = brute_distance(solid.mesh, p);
      ASSERT_NEAR(result.distance_m, expected, 1e-9) << p.transpose();
      ASSERT_NEAR((result.point - p).norm(), expected, 1e-9);
      // The point lies on the face it names.
      const auto& f = solid.mesh.faces[result.face];
      const Eigen::Vector3d on_face =
          brute_closest_on_triangle(result.point, solid.mesh.vertices[f[0]],
                                    solid.mesh.vertices[f[1]], solid.mesh.vertices[f[2]]);
      ASSERT_LT((on_face - result.point).norm(), 1e-9);
      on_edges += result.feature == MeshFeature::kEdge;
      on_vertices += result.feature == MeshFeature::kVertex;
      if (expected < 1e-9) continue;  // on the surface: no side to check
      ++checked_signs;
      ASSERT_EQ(result.signed_distance_m < 0, solid.inside(p))
          << p.transpose() << " signed " << result.signed_distance_m << " face " << result.face
          << " feature " << static_cast<int>(result.feature) << " normal "
          << result.normal.transpose();
      ASSERT_NEAR(std::abs(result.signed_distance_m), expected, 1e-9);
    }
    // The near-feature queries did exercise the pseudonormals.
    EXPECT_GT(on_edges, 100);
    EXPECT_GT(on_vertices, 50);
    EXPECT_GT(checked_signs, 2900);
  }
}

TEST(MeshQuery, RaycastMatchesBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-3, 3);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> range(0.5, 6);
  for (const Solid& solid : solids()) {
    SCOPED_TRACE(solid.name);
    const MeshQuery query(solid.mesh);
    int hits = 0;
    for (int i = 0; i < 3000; ++i) {
      Ray ray;
      ray.origin = {u(rng), u(rng), u(rng)};
      ray.direction = {g(rng), g(rng), g(rng)};
      if (i % 2 == 0) {  // aim at a vertex, give or take, so that many rays hit
        const auto& f = solid.mesh.faces[i % solid.mesh.faces.size()];
        ray.direction = solid.mesh.vertices[f[0]] + 0.05 * ray.direction - ray.origin;
      }
      ray.max_range_m = range(rng);
      const Eigen::Vector3d d = ray.direction.normalized();
      const auto expected = brute_raycast(solid.mesh, ray.origin, d, ray.max_range_m);
      const auto hit = query.raycast(ray);
      ASSERT_EQ(hit.has_value(), expected.has_value()) << i;
      if (!hit) continue;
      ++hits;
      ASSERT_NEAR(hit->distance_m, expected->first, 1e-9);
      ASSERT_LT((hit->point - (ray.origin + expected->first * d)).norm(), 1e-9);
      const auto& f = solid.mesh.faces[hit->face];
      const Eigen::Vector3d n = (solid.mesh.vertices[f[1]] - solid.mesh.vertices[f[0]])
                                    .cross(solid.mesh.vertices[f[2]] - solid.mesh.vertices[f[0]])
                                    .normalized();
      ASSERT_LT((hit->face_normal - n).norm(), 1e-12);
      // The hit face is the brute-force face, or one at the same distance (shared edge).
      if (hit->face != expected->second) {
        ASSERT_LT(std::abs(brute_distance(solid.mesh, hit->point)), 1e-9);
      }
    }
    EXPECT_GT(hits, 300);
  }
}

// Hits of two rays from the origin through the point a + t (b - a) of edge (a, b), nudged
// 1e-7 to either side of the edge: one on each face of the edge.
std::array<std::optional<RayHit>, 2> hits_either_side(const MeshQuery& query,
                                                      const Eigen::Vector3d& a,
                                                      const Eigen::Vector3d& b, double t) {
  const Eigen::Vector3d on_edge = a + t * (b - a);
  const Eigen::Vector3d across = (b - a).cross(on_edge).normalized();
  std::array<std::optional<RayHit>, 2> side;
  for (int k = 0; k < 2; ++k) {
    Ray ray;
    ray.direction = on_edge + (k == 0 ? 1e-7 : -1e-7) * across;
    side[k] = query.raycast(ray);
  }
  return side;
}

// RayHit::interpolated_normal: continuous across the edges of a tessellated sphere and closer
// to the sphere's true normal than the facets'; equal to the face normal on a box, whose
// edges are 90-degree creases.
TEST(MeshQuery, InterpolatedNormalIsSmoothOnCurvesAndFlatOnCreases) {
  const double radius = 4.0;
  const TriangleMesh sphere = testing::make_icosphere(3, radius);
  const MeshQuery query(sphere);
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0, 1);
  double facet_error = 0, interpolated_error = 0;
  int edges = 0;
  for (int i = 0; i < 400; ++i) {
    // A ray from the centre through a point of edge (a, b), nudged to either side of it.
    const auto& f = sphere.faces[i % sphere.faces.size()];
    const auto side = hits_either_side(query, sphere.vertices[f[0]], sphere.vertices[f[1]],
                                       0.2 + 0.6 * (i % 7) / 6.0);
    for (int k = 0; k < 2; ++k) {
      ASSERT_TRUE(side[k]);
      const Eigen::Vector3d truth = side[k]->point.normalized();
      facet_error += std::acos(std::min(1.0, side[k]->face_normal.dot(truth)));
      interpolated_error += std::acos(std::min(1.0, side[k]->interpolated_normal.dot(truth)));
    }
    ASSERT_NE(side[0]->face, side[1]->face) << i;
    EXPECT_GT((side[0]->face_normal - side[1]->face_normal).norm(), 0.05) << i;  // the kink
    EXPECT_LT((side[0]->interpolated_normal - side[1]->interpolated_normal).norm(), 1e-5) << i;
    ++edges;
  }
  // On a level-3 icosphere (edges ~0.08 R) the facet normals are off by ~2 degrees on average.
  EXPECT_LT(interpolated_error, 0.1 * facet_error) << "over " << 2 * edges << " hits";

  const MeshQuery box(testing::make_box({-1, -2, -3}, {1, 2, 3}));
  for (int i = 0; i < 300; ++i) {
    Ray ray;
    ray.direction = {g(rng), g(rng), g(rng)};
    const auto hit = box.raycast(ray);  // from inside: every ray hits
    ASSERT_TRUE(hit);
    EXPECT_LT((hit->interpolated_normal - hit->face_normal).norm(), 1e-12) << i;
  }
}

// On a level-1 icosphere every edge turns by ~20 degrees (a smooth edge) but faces two steps
// round a vertex by ~40: the smoothing group, not a per-face angle test, decides what a
// corner blends, so both faces of every edge blend the same normals along it.
TEST(MeshQuery, InterpolatedNormalIsContinuousAcrossEverySmoothEdge) {
  const TriangleMesh sphere = testing::make_icosphere(1, 2.0);
  const MeshQuery query(sphere);
  int edges = 0;
  for (const auto& f : sphere.faces) {
    for (int e = 0; e < 3; ++e) {
      for (const double t : {0.1, 0.5, 0.9}) {
        const auto side =
            hits_either_side(query, sphere.vertices[f[e]], sphere.vertices[f[(e + 1) % 3]], t);
        ASSERT_TRUE(side[0] && side[1]);
        ASSERT_NE(side[0]->face, side[1]->face);
        ASSERT_LT(std::acos(side[0]->face_normal.dot(side[1]->face_normal)), 30.0 * M_PI / 180);
        EXPECT_LT((side[0]->interpolated_normal - side[1]->interpolated_normal).norm(), 1e-5)
            << "edge " << f[e] << "-" << f[(e + 1) % 3] << " at " << t;
        ++edges;
      }
    }
  }
  EXPECT_EQ(edges, 3 * 3 * 80);
}

// A fan of 10k faces that all list the shared vertex first: CGAL's distance-query k-d tree on
// one vertex per triangle recursed until the stack overflowed. The fan is flat (z = 0).
TEST(MeshQuery, LargeFanListingTheSharedVertexFirst) {
  TriangleMesh fan;
  const int n = 10000;
  fan.vertices.emplace_back(0, 0, 0);
  for (int i = 0; i < n; ++i) {
    const double angle = 2 * M_PI * i / n;
    fan.vertices.emplace_back(std::cos(angle), std::sin(angle), 0);
  }
  for (int i = 0; i < n; ++i) fan.faces.emplace_back(0, 1 + i, 1 + (i + 1) % n);
  const MeshQuery query(fan);
  EXPECT_EQ(query.num_faces(), static_cast<size_t>(n));
  const ClosestPoint closest = query.closest_point({0.3, -0.2, 0.5});
  EXPECT_NEAR(closest.distance_m, 0.5, 1e-12);
  EXPECT_LT((closest.point - Eigen::Vector3d(0.3, -0.2, 0)).norm(), 1e-9);
  Ray ray;
  ray.origin = {0.2, 0.1, -1};
  ray.direction = {0, 0, 1};
  const auto hit = query.raycast(ray);
  ASSERT_TRUE(hit);
  EXPECT_LT((hit->interpolated_normal - Eigen::Vector3d::UnitZ()).norm(), 1e-12);  // flat
}

TEST(MeshQuery, BatchesEqualSingleQueries) {
  const TriangleMesh mesh = testing::make_icosphere(3);
  const MeshQuery query(mesh);
  std::mt19937 rng(1);
  const auto points = queries_near(mesh, rng, 500);
  std::vector<Ray> rays;
  for (const auto& p : points) rays.push_back({3 * p, -p, 10, 0});
  for (const int threads : {1, 2}) {
    const auto closest = query.closest_points(points, threads);
    const auto signed_distances = query.signed_distances(points, threads);
    const auto hits = query.raycasts(rays, threads);
    for (size_t i = 0; i < points.size(); ++i) {
      const ClosestPoint single = query.closest_point(points[i]);
      EXPECT_EQ(closest[i].point, single.point);
      EXPECT_EQ(closest[i].face, single.face);
      EXPECT_EQ(signed_distances[i], single.signed_distance_m);
      const auto hit = query.raycast(rays[i]);
      ASSERT_EQ(hits[i].has_value(), hit.has_value());
      if (hit) {
        EXPECT_EQ(hits[i]->distance_m, hit->distance_m);
      }
    }
  }
}

TEST(MeshQuery, FacesWithinMatchesBruteForce) {
  std::mt19937 rng(5);
  for (const Solid& solid : solids()) {
    SCOPED_TRACE(solid.name);
    const MeshQuery query(solid.mesh);
    std::uniform_real_distribution<double> radius(0.0, 0.8);
    for (const Eigen::Vector3d& p : queries_near(solid.mesh, rng, 300)) {
      const double r = radius(rng);
      std::vector<double> distances;
      std::vector<int> faces = query.faces_within(p, r, &distances);
      ASSERT_EQ(faces.size(), distances.size());
      std::sort(faces.begin(), faces.end());
      std::vector<int> expected;
      for (size_t f = 0; f < solid.mesh.faces.size(); ++f) {
        const auto& v = solid.mesh.faces[f];
        const double d =
            (p - brute_closest_on_triangle(p, solid.mesh.vertices[v[0]], solid.mesh.vertices[v[1]],
                                           solid.mesh.vertices[v[2]]))
                .norm();
        // Faces within rounding of the sphere may go either way.
        if (std::abs(d - r) < 1e-12) {
          expected.clear();
          break;
        }
        if (d < r) expected.push_back(static_cast<int>(f));
      }
      if (expected.empty() && !faces.empty()) continue;  // a face on the sphere (rare)
      ASSERT_EQ(faces, expected) << p.transpose() << " r " << r;
    }
  }
}

// LocalClosestPoint against brute force over all triangles, on points that move: random walks
// with small steps (cache hits), occasional jumps (re-anchoring), walks across edges, vertices
// and the inside, and a tight candidate budget that makes the move bound shrink.
TEST(LocalClosestPoint, EqualsBruteForceOnMovingPoints) {
  std::mt19937 rng(11);
  std::normal_distribution<double> step(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Solid& solid : solids()) {
    for (const int max_candidates : {48, 4}) {
      SCOPED_TRACE(solid.name + " max_candidates " + std::to_string(max_candidates));
      const MeshQuery query(solid.mesh);
      LocalClosestPointOptions options;
      options.move_bound_m = 0.1;
      options.max_candidates = max_candidates;
      int cached = 0, total = 0, shrunk = 0;
      for (const Eigen::Vector3d& start : queries_near(solid.mesh, rng, 40)) {
        LocalClosestPoint local(query, options);
        Eigen::Vector3d p = start;
        for (int k = 0; k < 60; ++k) {
          // Mostly millimetre to centimetre steps, sometimes a 0.3 m jump.
          const double scale = unit(rng) < 0.05 ? 0.3 : (unit(rng) < 0.5 ? 0.002 : 0.02);
          p += scale * Eigen::Vector3d(step(rng), step(rng), step(rng));
          const ClosestPoint result = local.closest_point(p);
          const ClosestPoint tree = query.closest_point(p);
          const double expected = brute_distance(solid.mesh, p);
          ASSERT_NEAR(result.distance_m, expected, 1e-9) << p.transpose();
          ASSERT_NEAR((result.point - p).norm(), expected, 1e-9);
          ASSERT_LT((result.point - tree.point).norm(), 1e-9) << p.transpose();
          ASSERT_NEAR(result.signed_distance_m, tree.signed_distance_m, 1e-9) << p.transpose();
          ASSERT_LT((result.normal - tree.normal).norm(), 1e-9) << p.transpose();
          // The face it names holds the point.
          const auto& f = solid.mesh.faces[result.face];
          const Eigen::Vector3d on_face =
              brute_closest_on_triangle(result.point, solid.mesh.vertices[f[0]],
                                        solid.mesh.vertices[f[1]], solid.mesh.vertices[f[2]]);
          ASSERT_LT((on_face - result.point).norm(), 1e-9);
          ++total;
          shrunk += local.move_bound_m() < options.move_bound_m;
        }
        cached += local.cached_queries();
        EXPECT_EQ(local.cached_queries() + local.tree_queries(), 60);
      }
      // The cache did answer many calls, so the comparison above exercised it.
      EXPECT_GT(cached, max_candidates == 4 ? total / 4 : total / 2);
      if (max_candidates == 4) {
        EXPECT_GT(shrunk, 0);
      }
    }
  }
}

// A rejected Levenberg-Marquardt step: the point jumps and comes back. The jump is answered
// exactly by the tree and the anchor stays; a point that stays after its jump is re-anchored.
TEST(LocalClosestPoint, JumpAndReturnKeepsTheAnchor) {
  const TriangleMesh mesh = testing::make_box({0, 0, 0}, {1, 1, 1});
  const MeshQuery query(mesh);
  LocalClosestPoint local(query);  // rho = 5 cm
  const Eigen::Vector3d start(0.5, 0.4, 1.02);
  local.closest_point(start);
  EXPECT_EQ(local.tree_queries(), 1);
  const Eigen::Vector3d jump(1.3, 0.4, 0.5);
  EXPECT_NEAR(local.closest_point(jump).signed_distance_m, 0.3, 1e-12);
  EXPECT_EQ(local.tree_queries(), 2);
  EXPECT_NEAR(local.closest_point(start + Eigen::Vector3d(0.01, 0, 0)).signed_distance_m, 0.02,
              1e-12);
  EXPECT_EQ(local.cached_queries(), 1);  // back at the anchor: no tree query
  local.closest_point(jump);
  EXPECT_NEAR(local.closest_point(jump + Eigen::Vector3d(0, 0.01, 0)).signed_distance_m, 0.3,
              1e-12);
  EXPECT_EQ(local.tree_queries(), 4);  // it stayed: re-anchored there
  EXPECT_NEAR(local.closest_point(jump + Eigen::Vector3d(0, 0.02, 0)).distance_m, 0.3, 1e-12);
  EXPECT_EQ(local.cached_queries(), 2);
}

TEST(LocalClosestPoint, FarPointsAndBadInput) {
  const TriangleMesh mesh = testing::make_icosphere(3);
  const MeshQuery query(mesh);
  LocalClosestPointOptions options;
  options.max_candidates = 8;
  options.min_move_bound_m = 0.04;
  LocalClosestPoint local(query, options);
  // From 5 m away, more than 8 faces lie within d0 + 2 rho and the 9th is closer than
  // d0 + 2 min_move_bound_m: nothing worth caching, every call asks the tree.
  for (int k = 0; k < 5; ++k) {
    const Eigen::Vector3d p(6.0 + 0.001 * k, 0.2, 0.1);
    EXPECT_NEAR(local.closest_point(p).distance_m, brute_distance(mesh, p), 1e-9);
  }
  EXPECT_EQ(local.tree_queries(), 5);
  EXPECT_EQ(local.num_candidates(), 0u);
  EXPECT_THROW(local.closest_point({std::nan(""), 0, 0}), std::invalid_argument);
  options.move_bound_m = 0;
  EXPECT_THROW(LocalClosestPoint(query, options), std::invalid_argument);
  EXPECT_THROW(query.closest_point_among({0, 0, 0}, {}), std::invalid_argument);
  EXPECT_THROW(query.closest_point_among({0, 0, 0}, {-1}), std::invalid_argument);
  EXPECT_THROW(query.faces_within({0, 0, 0}, -1.0), std::invalid_argument);
}

TEST(MeshQuery, DegenerateFacesAndBadInput) {
  TriangleMesh mesh = testing::make_box({0, 0, 0}, {1, 1, 1});
  mesh.faces.emplace_back(0, 0, 1);  // repeated index
  mesh.vertices.emplace_back(0.5, 0, 0);
  mesh.faces.emplace_back(0, 1, 8);  // zero area, on an edge of the box
  const MeshQuery query(mesh);
  EXPECT_EQ(query.num_faces(), 12u);
  EXPECT_NEAR(query.signed_distance({0.5, -1, 0.5}), 1.0, 1e-12);
  EXPECT_THROW(query.raycast({{0, 0, 0}, {0, 0, 0}, 1}), std::invalid_argument);
  EXPECT_THROW(query.closest_point({std::nan(""), 0, 0}), std::invalid_argument);
  EXPECT_THROW(query.raycasts({Ray{}, Ray{{0, 0, 0}, {0, 0, 0}, 1}}, 2), std::invalid_argument);
  mesh.faces.emplace_back(0, 1, 42);
  EXPECT_THROW(MeshQuery{mesh}, std::invalid_argument);
  TriangleMesh flat;
  flat.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.faces = {{0, 1, 2}};
  EXPECT_THROW(MeshQuery{flat}, std::invalid_argument);
}

}  // namespace
}  // namespace keel::ba
