// The cutting-plane medoid against the O(n^2) definition.
#include "worker/mapping/medoid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace keel::mapping {
namespace {

// Sum of distances from member m, in double.
double distance_sum(const std::vector<float>& x, const std::vector<float>& y,
                    const std::vector<float>& z, size_t m) {
  double sum = 0.0;
  for (size_t k = 0; k < x.size(); ++k) {
    sum += std::sqrt(std::pow(double(x[k]) - x[m], 2) + std::pow(double(y[k]) - y[m], 2) +
                     std::pow(double(z[k]) - z[m], 2));
  }
  return sum;
}

TEST(Medoid, MatchesBruteForceOnPlanesBlobsAndLines) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.25f, 0.25f);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  MedoidScratch scratch;
  int total_evaluations = 0, total_points = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const size_t n = 1 + trial % 150;
    std::vector<float> x, y, z;
    for (size_t k = 0; k < n; ++k) {
      switch (trial % 3) {
        case 0:  // noisy plane patch
          x.push_back(u(rng)), y.push_back(u(rng)), z.push_back(noise(rng));
          break;
        case 1:  // volume
          x.push_back(u(rng)), y.push_back(u(rng)), z.push_back(u(rng));
          break;
        default:  // line, with duplicates
          x.push_back(k % 7 == 0 && k > 0 ? x.back() : u(rng)), y.push_back(0.0f),
              z.push_back(0.0f);
      }
    }
    double best = std::numeric_limits<double>::infinity();
    for (size_t m = 0; m < n; ++m) best = std::min(best, distance_sum(x, y, z, m));
    const MedoidResult result = exact_medoid(x.data(), y.data(), z.data(), n, &scratch);
    ASSERT_LT(result.index, n);
    // Exact up to ties within float rounding of the sums.
    EXPECT_NEAR(distance_sum(x, y, z, result.index), best, 2e-5 * best + 1e-9) << trial;
    EXPECT_NEAR(result.distance_sum, best, 2e-5 * best + 1e-9) << trial;
    total_evaluations += result.evaluations;
    total_points += static_cast<int>(n);
  }
  // The cuts must prune: far fewer evaluations than members.
  EXPECT_LT(total_evaluations, total_points / 4);
}

TEST(Medoid, SinglePointAndIdenticalPoints) {
  MedoidScratch scratch;
  const std::vector<float> one{1.0f};
  EXPECT_EQ(exact_medoid(one.data(), one.data(), one.data(), 1, &scratch).index, 0u);
  const std::vector<float> same(5, 0.5f);
  const MedoidResult r = exact_medoid(same.data(), same.data(), same.data(), 5, &scratch);
  EXPECT_LT(r.index, 5u);
  EXPECT_EQ(r.distance_sum, 0.0);
}

}  // namespace
}  // namespace keel::mapping
