// Eqs. (23)-(26) on analytic surfaces, density against brute-force counts.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <atomic>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "tests/worker/mapping/test_clouds.h"
#include "worker/mapping/map_metrics.h"

namespace keel::mapping {
namespace {

std::vector<float> values_at(const PointMetrics& metrics, const std::vector<float>& values,
                             const std::vector<Eigen::Vector3f>& points,
                             bool (*keep)(const Eigen::Vector3f&)) {
  std::vector<float> out;
  for (size_t q = 0; q < metrics.query_index.size(); ++q) {
    if (keep(points[metrics.query_index[q]])) out.push_back(values[q]);
  }
  return out;
}

TEST(MapMetrics, NoisyPlane) {
  // z ~ N(0, sigma) on a 2 cm square lattice over 4 m x 4 m (2500 points/m^2). A lattice, not
  // random x, y: a disc of lattice points about a lattice point has l1 = l2 exactly, where a
  // random sample of ~490 points would split them by a few percent and bias planarity low.
  const double sigma = 0.005;
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(sigma));
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 200; ++i) {
    for (int j = 0; j < 200; ++j) points.emplace_back(0.02f * i, 0.02f * j, noise(rng));
  }
  MapMetricsOptions options;
  options.max_query_points = 4000;
  const PointMetrics metrics = compute_point_metrics(points, options);
  // Interior points only: a neighbourhood cut by the edge is a half disc.
  auto interior = [](const Eigen::Vector3f& p) {
    return std::abs(p.x() - 2.0f) < 1.7f && std::abs(p.y() - 2.0f) < 1.7f;
  };
  const Distribution roughness =
      summarize(values_at(metrics, metrics.roughness, points, interior), 10);
  const Distribution planarity =
      summarize(values_at(metrics, metrics.planarity, points, interior), 10);
  ASSERT_GT(roughness.count, 2000u);
  // Roughness is |z - plane| for z ~ N(0, sigma): a half-normal, mean sigma * sqrt(2 / pi).
  EXPECT_NEAR(roughness.mean, sigma * std::sqrt(2.0 / M_PI), 0.05 * sigma * std::sqrt(2.0 / M_PI));
  // ... and median sigma * 0.6745 (the half-normal's median).
  EXPECT_NEAR(roughness.median, 0.6745 * sigma, 0.08 * 0.6745 * sigma);
  // Disc of radius r: l1 = l2 = r^2 / 4, l3 = sigma^2, planarity = 1 - 4 sigma^2 / r^2 = 0.9984.
  EXPECT_NEAR(planarity.mean, 1.0 - 4.0 * sigma * sigma / (0.25 * 0.25), 0.01);
  EXPECT_GT(planarity.p05, 0.95);
  // Surface density of the interior: 40000 / 16 m^2.
  const Distribution density =
      summarize(values_at(metrics, metrics.surface_density, points, interior), 10);
  EXPECT_NEAR(density.mean, 2500.0, 2500.0 * 0.02);
}

TEST(MapMetrics, SphereMatchesSphericalCapClosedForms) {
  // Uniform points on a sphere of radius R = 0.5 m; neighbourhoods (r = 0.25 m) are caps with
  // cos(theta0) = c = 1 - r^2 / (2 R^2) = 0.875, u = cos(theta) uniform on [c, 1].
  const double R = 0.5, r = 0.25, c = 1.0 - r * r / (2 * R * R);
  // A Fibonacci lattice: near-uniform without the sampling anisotropy of random points.
  std::vector<Eigen::Vector3f> points;
  const int n = 60000;
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / n;
    const double rho = std::sqrt(1.0 - z * z);
    points.push_back(
        (R * Eigen::Vector3d(rho * std::cos(golden_angle * k), rho * std::sin(golden_angle * k), z))
            .cast<float>());
  }
  MapMetricsOptions options;
  options.max_query_points = 1500;
  const PointMetrics metrics = compute_point_metrics(points, options);
  const Distribution roughness = summarize(metrics.roughness, 10);
  const Distribution planarity = summarize(metrics.planarity, 10);
  // Least-squares plane through the cap's centroid, at height R (1 + c) / 2: the point is
  // R (1 - c) / 2 = r^2 / (4 R) = 0.03125 m above it.
  EXPECT_NEAR(roughness.mean, R * (1 - c) / 2, 0.03 * R * (1 - c) / 2);
  // Eq. (26) is taken about the medoid, the member nearest the cap's axis: its apex (the query
  // point), not the centroid. Tangential second moment R^2 (1 - E[u^2]) / 2, normal second
  // moment about the apex R^2 E[(1 - u)^2] = R^2 (1 - c)^2 / 3 (u uniform on [c, 1]).
  const double Eu2 = (1 - c * c * c) / (3 * (1 - c));
  const double tangential = R * R * (1 - Eu2) / 2, normal = R * R * (1 - c) * (1 - c) / 3;
  EXPECT_NEAR(planarity.mean, (tangential - normal) / tangential, 0.01);
  // Density: cap area 2 pi R^2 (1 - c) holds that share of the 60000 points of the sphere.
  const double expected_n = 60000.0 * (1 - c) / 2;
  EXPECT_NEAR(summarize(metrics.surface_density, 10).mean, expected_n / (M_PI * r * r),
              0.02 * expected_n / (M_PI * r * r));
}

TEST(MapMetrics, LineHasPlanarityNearZero) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 5.0f);
  std::normal_distribution<float> noise(0.0f, 0.002f);
  std::vector<Eigen::Vector3f> points;
  for (int k = 0; k < 20000; ++k) points.emplace_back(u(rng), noise(rng), noise(rng));
  MapMetricsOptions options;
  options.max_query_points = 2000;
  const PointMetrics metrics = compute_point_metrics(points, options);
  const Distribution planarity = summarize(metrics.planarity, 10);
  // l1 ~ r^2 / 3 (uniform along 2r), l2 ~ l3 ~ sigma^2: planarity ~ 0.
  EXPECT_LT(planarity.mean, 0.01);
  EXPECT_LT(planarity.p95, 0.02);
}

TEST(MapMetrics, DensityIsBruteForceCountOverDiscArea) {
  const PointCloud cloud = testing::random_cloud(3000, 0.0f, 1.0f, 4);
  MapMetricsOptions options;
  options.radius_m = 0.1;
  const PointMetrics metrics = compute_point_metrics(cloud.xyz, options);
  ASSERT_EQ(metrics.query_index.size(), cloud.size());
  size_t checked = 0;
  for (size_t q = 0; q < cloud.size(); ++q) {
    int count = 0;
    bool ambiguous = false;
    for (const auto& p : cloud.xyz) {
      const double d = (p - cloud.xyz[q]).cast<double>().norm();
      count += d < 0.1;
      ambiguous |= std::abs(d - 0.1) < 1e-6;
    }
    if (ambiguous) continue;
    ++checked;
    ASSERT_NEAR(metrics.surface_density[q], count / (M_PI * 0.01), 1e-3) << q;
  }
  EXPECT_GT(checked, 2900u);
}

// Eqs. (23)-(26) per point in double precision straight from their definitions: neighbours by
// brute force, roughness from the plane of the others, Sigma about the O(N^2) medoid.
struct Oracle {
  double density = 0, roughness = std::nan(""), planarity = std::nan("");
  bool ambiguous = false;  // a neighbour within 1e-5 m of the sphere: float may count it either way
};

Oracle brute_force(const std::vector<Eigen::Vector3f>& points, size_t q, double r) {
  Oracle o;
  const Eigen::Vector3d p = points[q].cast<double>();
  std::vector<Eigen::Vector3d> hood;
  for (const auto& v : points) {
    const double d = (v.cast<double>() - p).norm();
    if (d < r) hood.push_back(v.cast<double>());
    o.ambiguous |= std::abs(d - r) < 1e-5;
  }
  const size_t n = hood.size();
  o.density = n / (M_PI * r * r);
  if (n >= 4) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& v : hood) centroid += v;
    centroid = (centroid - p) / double(n - 1);  // q itself left out
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    bool skipped = false;
    for (const auto& v : hood) {
      if (!skipped && v == p) {
        skipped = true;
        continue;
      }
      cov += (v - centroid) * (v - centroid).transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov / double(n - 1));
    o.roughness = std::abs(solver.eigenvectors().col(0).dot(p - centroid));
  }
  if (n >= 3) {
    size_t medoid = 0;
    double best = std::numeric_limits<double>::infinity();
    for (size_t m = 0; m < n; ++m) {
      double sum = 0;
      for (const auto& v : hood) sum += (v - hood[m]).norm();
      if (sum < best) best = sum, medoid = m;
    }
    Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
    for (const auto& v : hood) sigma += (v - hood[medoid]) * (v - hood[medoid]).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(sigma / double(n));
    const Eigen::Vector3d l = solver.eigenvalues();
    o.planarity = (l[1] - l[0]) / l[2];
  }
  return o;
}

TEST(MapMetrics, EveryPointMatchesBruteForceOracle) {
  // A noisy plane crossing a uniform volume: planar, volumetric and mixed neighbourhoods.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  std::vector<Eigen::Vector3f> points;
  for (int k = 0; k < 1500; ++k) points.emplace_back(u(rng), u(rng), 0.5f + noise(rng));
  for (int k = 0; k < 1500; ++k) points.emplace_back(u(rng), u(rng), u(rng));
  MapMetricsOptions options;  // r = 0.25 m, 2 threads
  const PointMetrics metrics = compute_point_metrics(points, options);
  ASSERT_EQ(metrics.query_index.size(), points.size());
  size_t checked = 0;
  for (size_t q = 0; q < points.size(); q += 3) {
    ASSERT_EQ(metrics.query_index[q], q);
    const Oracle o = brute_force(points, q, options.radius_m);
    if (o.ambiguous) continue;
    ++checked;
    ASSERT_NEAR(metrics.surface_density[q], o.density, 1e-3) << q;
    ASSERT_NEAR(metrics.roughness[q], o.roughness, 1e-5 + 1e-3 * o.roughness) << q;
    ASSERT_NEAR(metrics.planarity[q], o.planarity, 1e-3) << q;
  }
  EXPECT_GT(checked, 900u);
}

TEST(MapMetrics, SummaryStatistics) {
  std::vector<float> values;
  for (int k = 1; k <= 100; ++k) values.push_back(static_cast<float>(k));
  values.push_back(std::nanf(""));
  const Distribution d = summarize(values, 4);
  EXPECT_EQ(d.count, 100u);
  EXPECT_EQ(d.undefined, 1u);
  EXPECT_DOUBLE_EQ(d.mean, 50.5);
  EXPECT_DOUBLE_EQ(d.median, 50.5);
  EXPECT_DOUBLE_EQ(d.p25, 25.75);  // numpy.percentile(range(1, 101), 25)
  EXPECT_DOUBLE_EQ(d.p95, 95.05);
  EXPECT_NEAR(d.std, std::sqrt((100.0 * 100.0 - 1.0) / 12.0), 1e-9);
  EXPECT_EQ(d.histogram_counts, (std::vector<size_t>{25, 25, 25, 25}));
  EXPECT_EQ(d.histogram_edges.size(), 5u);
}

TEST(MapMetrics, UndefinedWhereNeighbourhoodsAreTooSmall) {
  const std::vector<Eigen::Vector3f> points{{0, 0, 0}, {0.1f, 0, 0}, {5, 5, 5}};
  const PointMetrics metrics = compute_point_metrics(points);
  EXPECT_TRUE(std::isnan(metrics.roughness[0]));
  EXPECT_TRUE(std::isnan(metrics.planarity[2]));
  EXPECT_NEAR(metrics.surface_density[2], 1.0 / (M_PI * 0.0625), 1e-4);
  EXPECT_THROW(compute_point_metrics({{0, 0, std::nanf("")}}), std::invalid_argument);
}

TEST(MapMetrics, RadiusBeyondOneMetreIsRefused) {
  MapMetricsOptions options;
  for (const double r : {0.0, -0.25, 1.0001, 1e9, std::nan("")}) {
    options.radius_m = r;
    EXPECT_THROW(compute_point_metrics({{0, 0, 0}}, options), std::invalid_argument) << r;
  }
  options.radius_m = kMaxMetricsRadiusM;
  EXPECT_EQ(compute_point_metrics({{0, 0, 0}}, options).surface_density.size(), 1u);
}

TEST(MapMetrics, CancelCheckStopsTheComputation) {
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j) points.emplace_back(0.01f * i, 0.01f * j, 0.0f);
  MapMetricsOptions options;
  options.radius_m = 0.05;  // 400 cells of 5 cm, one check each
  options.threads = 2;
  std::atomic<int> calls{0};
  // Cancellation is sticky, as a job's is: every check from the 50th on throws. (Throwing
  // once only let the other thread run on while the first unwound, slowly on a loaded host.)
  options.check_canceled = [&calls] {
    if (++calls >= 50) throw std::runtime_error("canceled");
  };
  EXPECT_THROW(compute_point_metrics(points, options), std::runtime_error);
  EXPECT_LT(calls.load(), 10000);  // stopped long before every point was measured
  EXPECT_LT(calls.load(), 200);    // and before half the cells
}

}  // namespace
}  // namespace keel::mapping
