// C2C distances against the brute-force nearest neighbour (exact: same float result).
#include "worker/compare/c2c_distance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace keel::compare {
namespace {

float brute_force(const std::vector<Eigen::Vector3f>& reference, const Eigen::Vector3f& q) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : reference)
    best = std::min(best, (p.cast<double>() - q.cast<double>()).norm());
  return float(best);
}

TEST(C2cDistance, EqualsBruteForceOnRandomClouds) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coordinate(-5.0f, 5.0f);
  std::vector<Eigen::Vector3f> reference(4000), compared(1500);
  for (auto& p : reference) p = {coordinate(rng), coordinate(rng), 0.2f * coordinate(rng)};
  for (auto& p : compared) p = {coordinate(rng), coordinate(rng), coordinate(rng)};
  compared.push_back(reference[17]);  // a shared point: distance exactly 0
  const NearestIndex index(reference);
  const std::vector<float> d = c2c_distances(index, compared, 2);
  ASSERT_EQ(d.size(), compared.size());
  for (size_t i = 0; i < compared.size(); ++i)
    ASSERT_EQ(d[i], brute_force(reference, compared[i])) << "point " << i;
  EXPECT_EQ(d.back(), 0.0f);
}

TEST(C2cDistance, FarPointsAndSinglePointReference) {
  const std::vector<Eigen::Vector3f> reference = {{1.0f, 2.0f, 3.0f}};
  const NearestIndex index(reference);
  const std::vector<float> d = c2c_distances(index, {{4.0f, 6.0f, 3.0f}, {1.0f, 2.0f, 3.0f}});
  EXPECT_FLOAT_EQ(d[0], 5.0f);  // 3-4-5
  EXPECT_EQ(d[1], 0.0f);
}

TEST(C2cDistance, RefusesBadInput) {
  EXPECT_THROW(NearestIndex({}), std::invalid_argument);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(NearestIndex({{0, 0, 0}, {nan, 0, 0}}), std::invalid_argument);
  const NearestIndex index({{0, 0, 0}});
  EXPECT_THROW(c2c_distances(index, {{0, nan, 0}}), std::invalid_argument);
}

}  // namespace
}  // namespace keel::compare
