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

// Random members: noisy plane patches, volumes, lines with duplicates, and tight clusters
// (many near-ties) of 1..150 points (every remainder of the 4- and 8-lane kernels), plus a few
// of the size of 2 cm map neighbourhoods at r = 0.25 m.
std::vector<std::vector<float>> random_set(int trial, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-0.25f, 0.25f);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  const size_t n = trial < 400 ? 1 + trial % 150 : 1600;
  std::vector<float> x, y, z;
  for (size_t k = 0; k < n; ++k) {
    switch (trial % 4) {
      case 0:  // noisy plane patch
        x.push_back(u(rng)), y.push_back(u(rng)), z.push_back(noise(rng));
        break;
      case 1:  // volume
        x.push_back(u(rng)), y.push_back(u(rng)), z.push_back(u(rng));
        break;
      case 2:  // line, with duplicates
        x.push_back(k % 7 == 0 && k > 0 ? x.back() : u(rng)), y.push_back(0.0f), z.push_back(0.0f);
        break;
      default:  // two tight clusters
        x.push_back((k % 2 ? 0.1f : -0.1f) + 1e-3f * noise(rng)), y.push_back(1e-3f * noise(rng)),
            z.push_back(1e-3f * noise(rng));
    }
  }
  return {x, y, z};
}

void expect_matches_brute_force(bool baseline_kernels) {
  std::mt19937 rng(7);
  MedoidScratch scratch;
  scratch.baseline_kernels = baseline_kernels;
  int total_evaluations = 0, total_points = 0;
  int per_kind[4] = {0, 0, 0, 0};
  for (int trial = 0; trial < 408; ++trial) {
    const std::vector<std::vector<float>> set = random_set(trial, rng);
    const std::vector<float>&x = set[0], &y = set[1], &z = set[2];
    const size_t n = x.size();
    double best = std::numeric_limits<double>::infinity();
    for (size_t m = 0; m < n; ++m) best = std::min(best, distance_sum(x, y, z, m));
    const MedoidResult result = exact_medoid(x.data(), y.data(), z.data(), n, &scratch);
    ASSERT_LT(result.index, n);
    // Exact up to ties within float rounding of the sums.
    EXPECT_NEAR(distance_sum(x, y, z, result.index), best, 2e-5 * best + 1e-9) << trial;
    EXPECT_NEAR(result.distance_sum, best, 2e-5 * best + 1e-9) << trial;
    total_evaluations += result.evaluations;
    total_points += static_cast<int>(n);
    per_kind[trial % 4] += result.evaluations;
  }
  // The bounds must prune: a handful of evaluations per set, not one per member (102 sets of
  // each kind; the centroid's evaluation counted).
  EXPECT_LT(per_kind[0] + per_kind[1], 2 * 102 * 4);  // planes, volumes: F curves up
  EXPECT_LT(per_kind[2], 102 * 10);                   // lines: F is piecewise linear
  EXPECT_LT(per_kind[3], 102 * 16);                   // two clusters: near-ties
  EXPECT_LT(total_evaluations, total_points / 15);
}

TEST(Medoid, MatchesBruteForce) { expect_matches_brute_force(false); }

TEST(Medoid, BaselineKernelsMatchBruteForce) { expect_matches_brute_force(true); }

TEST(Medoid, SinglePointAndIdenticalPoints) {
  for (const bool baseline_kernels : {false, true}) {
    MedoidScratch scratch;
    scratch.baseline_kernels = baseline_kernels;
    const std::vector<float> one{1.0f};
    EXPECT_EQ(exact_medoid(one.data(), one.data(), one.data(), 1, &scratch).index, 0u);
    const std::vector<float> same(13, 0.5f);
    const MedoidResult r = exact_medoid(same.data(), same.data(), same.data(), 13, &scratch);
    EXPECT_LT(r.index, 13u);
    EXPECT_EQ(r.distance_sum, 0.0);
  }
}

}  // namespace
}  // namespace keel::mapping
