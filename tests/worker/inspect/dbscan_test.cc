// DBSCAN (Algorithm 1, line 11, seed 001) against a brute-force O(n^2) reference.
#include "worker/inspect/dbscan.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

namespace keel::inspect {
namespace {

// Textbook DBSCAN (Ester et al. 1996) with a linear scan for every neighbourhood: the oracle.
std::vector<int> brute_force_dbscan(const std::vector<Eigen::Vector3d>& points, double eps,
                                    int min_pts) {
  const int n = static_cast<int>(points.size());
  auto neighbours = [&](int i) {
    std::vector<int> out;
    for (int j = 0; j < n; ++j) {
      if ((points[j] - points[i]).squaredNorm() <= eps * eps) out.push_back(j);
    }
    return out;
  };
  std::vector<int> label(n, -2);  // -2 unvisited, -1 noise
  int cluster = 0;
  for (int i = 0; i < n; ++i) {
    if (label[i] != -2) continue;
    std::vector<int> stack = neighbours(i);  // depth-first, unlike dbscan()'s queue
    if (static_cast<int>(stack.size()) < min_pts) {
      label[i] = -1;
      continue;
    }
    label[i] = cluster;
    while (!stack.empty()) {
      const int q = stack.back();
      stack.pop_back();
      if (label[q] == -1) label[q] = cluster;
      if (label[q] != -2) continue;
      label[q] = cluster;
      const std::vector<int> more = neighbours(q);
      if (static_cast<int>(more.size()) < min_pts) continue;
      for (const int m : more) stack.push_back(m);
    }
    ++cluster;
  }
  return label;
}

// Same partition up to renaming the clusters, and the same noise set.
void expect_same_partition(const std::vector<int>& a, const std::vector<int>& b) {
  ASSERT_EQ(a.size(), b.size());
  std::map<int, int> a_to_b, b_to_a;
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i] == kDbscanNoise, b[i] == kDbscanNoise) << "point " << i;
    if (a[i] == kDbscanNoise) continue;
    const auto [ia, new_a] = a_to_b.emplace(a[i], b[i]);
    const auto [ib, new_b] = b_to_a.emplace(b[i], a[i]);
    ASSERT_EQ(ia->second, b[i]) << "point " << i;
    ASSERT_EQ(ib->second, a[i]) << "point " << i;
  }
}

std::vector<Eigen::Vector3d> random_clusters(uint32_t seed, int num_clusters, int per_cluster,
                                             int num_noise, double sigma) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> box(-2.0, 2.0);
  std::normal_distribution<double> normal(0.0, sigma);
  std::vector<Eigen::Vector3d> points;
  for (int c = 0; c < num_clusters; ++c) {
    const Eigen::Vector3d centre(box(rng), box(rng), 0.2 * box(rng));
    for (int k = 0; k < per_cluster; ++k) {
      points.push_back(centre + Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
    }
  }
  for (int k = 0; k < num_noise; ++k) points.emplace_back(box(rng), box(rng), 0.2 * box(rng));
  std::shuffle(points.begin(), points.end(), rng);
  return points;
}

TEST(Dbscan, MatchesBruteForceOnRandomClusters) {
  for (uint32_t seed = 1; seed <= 12; ++seed) {
    const auto points = random_clusters(seed, 6, 40, 150, 0.05);
    for (const double eps : {0.05, 0.12, 0.3}) {
      for (const int min_pts : {1, 3, 6}) {
        SCOPED_TRACE(::testing::Message()
                     << "seed " << seed << " eps " << eps << " min_pts " << min_pts);
        const std::vector<int> labels = dbscan(points, {eps, min_pts});
        const std::vector<int> reference = brute_force_dbscan(points, eps, min_pts);
        expect_same_partition(labels, reference);
        EXPECT_EQ(num_clusters(labels), num_clusters(reference));
      }
    }
  }
}

TEST(Dbscan, FindsWellSeparatedClustersAndNoise) {
  // Three tight blobs 1 m apart and two isolated points: min_pts 3 leaves the loners as noise
  // (section 4.2.1, seed 001: outlying features "are not detected as foreign shapes").
  std::vector<Eigen::Vector3d> points;
  for (int c = 0; c < 3; ++c) {
    for (int k = 0; k < 5; ++k) points.emplace_back(c * 1.0 + 0.02 * k, 0.0, 0.0);
  }
  points.emplace_back(5.0, 5.0, 0.0);
  points.emplace_back(-5.0, 5.0, 0.0);
  const std::vector<int> labels = dbscan(points, {0.12, 3});
  EXPECT_EQ(num_clusters(labels), 3);
  for (int c = 0; c < 3; ++c) {
    for (int k = 0; k < 5; ++k) EXPECT_EQ(labels[5 * c + k], c);
  }
  EXPECT_EQ(labels[15], kDbscanNoise);
  EXPECT_EQ(labels[16], kDbscanNoise);
}

TEST(Dbscan, BorderPointsAndClosedBall) {
  // 0, 0.5, 1.0 (exact in binary) with eps 0.5: the middle point has 3 neighbours in the closed
  // ball, the ends 2 -> one cluster of a core point and two border points.
  const std::vector<Eigen::Vector3d> line = {{0, 0, 0}, {0.5, 0, 0}, {1.0, 0, 0}};
  EXPECT_EQ(dbscan(line, {0.5, 3}), (std::vector<int>{0, 0, 0}));
  // Needing 4 neighbours, nobody is core.
  EXPECT_EQ(dbscan(line, {0.5, 4}), (std::vector<int>(3, kDbscanNoise)));
  // Just below the spacing, nothing touches.
  EXPECT_EQ(dbscan(line, {0.499, 2}), (std::vector<int>(3, kDbscanNoise)));
}

TEST(Dbscan, EmptyInputAndBadArguments) {
  EXPECT_TRUE(dbscan({}, {0.12, 3}).empty());
  EXPECT_THROW(dbscan({{0, 0, 0}}, {0.0, 3}), std::invalid_argument);
  EXPECT_THROW(dbscan({{0, 0, 0}}, {0.1, 0}), std::invalid_argument);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  try {
    dbscan({{0, 0, 0}, {nan, 0, 0}}, {0.1, 3});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace keel::inspect
