// How far a shape's top may lie beyond its highest feature (top_sampling.h), against closed
// forms and the order statistics of uniform samples.
#include "worker/inspect/top_sampling.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace keel::inspect {
namespace {

TEST(TopSampling, MeanSpacingOfTheHighestSites) {
  // Sites 0.30, 0.27, 0.25, 0.20, 0.19, 0.05: four spacings span 0.30 - 0.19.
  EXPECT_NEAR(top_sampling_sigma({0.05, 0.25, 0.19, 0.30, 0.20, 0.27}, {0.0, 4}), 0.11 / 4, 1e-15);
  EXPECT_NEAR(top_sampling_sigma({0.05, 0.25, 0.19, 0.30, 0.20, 0.27}, {0.0, 1}), 0.03, 1e-15);
  // Fewer sites than spacings + 1: the spacings there are.
  EXPECT_NEAR(top_sampling_sigma({0.1, 0.3}, {0.0, 4}), 0.2, 1e-15);
  // One height, or none: nothing beyond it to estimate from.
  EXPECT_EQ(top_sampling_sigma({0.11, 0.11, 0.11}, {0.0, 4}), 0.0);
  EXPECT_EQ(top_sampling_sigma({0.11}, {0.0, 4}), 0.0);
  EXPECT_EQ(top_sampling_sigma({}, {0.0, 4}), 0.0);
}

TEST(TopSampling, FeaturesOfOneSiteCountOnce) {
  // Three features per texture blob, 1 mm apart in height: with a 3 mm resolution the blobs
  // are the sites, 2 cm apart, and the estimate is their spacing. Counted as 15 independent
  // heights the spacings read ~4x smaller.
  std::vector<double> heights;
  for (int blob = 0; blob < 5; ++blob)
    for (int f = 0; f < 3; ++f) heights.push_back(0.12 - 0.02 * blob - 0.001 * f);
  EXPECT_NEAR(top_sampling_sigma(heights, {0.003, 4}), 0.02, 1e-12);
  EXPECT_NEAR(top_sampling_sigma(heights, {0.0, 4}), (0.12 - 0.099) / 4, 1e-12);
}

TEST(TopSampling, EstimatesTheGapToTheTopOfUniformHeights) {
  // n heights uniform on [H - L, H] (a dome's top, sampled evenly over its area): every
  // spacing of the order statistics, the gap H - max included, has mean L / (n + 1). The
  // estimate must match the true gap's mean. For large n the spacings are independent
  // exponentials: the gap G ~ Exp(1) and the estimate S / k with S ~ Gamma(k, 1), so
  // P(G <= t S / k) = 1 - E[exp(-t S / k)] = 1 - (k / (k + t))^k: 0.893 for t = 3, k = 4.
  std::mt19937 rng(7);
  const double top_m = 0.14, span_m = 0.06;
  std::uniform_real_distribution<double> height(top_m - span_m, top_m);
  for (const int n : {10, 30}) {
    double sum_gap = 0.0, sum_estimate = 0.0;
    int within = 0;
    const int trials = 20000;
    for (int t = 0; t < trials; ++t) {
      std::vector<double> h(n);
      for (double& x : h) x = height(rng);
      const double gap = top_m - *std::max_element(h.begin(), h.end());
      const double estimate = top_sampling_sigma(h, {0.0, 4});
      sum_gap += gap;
      sum_estimate += estimate;
      within += gap <= 3.0 * estimate;
    }
    const double expected = span_m / (n + 1);
    EXPECT_NEAR(sum_gap / trials, expected, 0.02 * expected) << n;
    EXPECT_NEAR(sum_estimate / trials, expected, 0.02 * expected) << n;
    const double coverage = 1.0 - std::pow(4.0 / 7.0, 4);
    EXPECT_NEAR(static_cast<double>(within) / trials, coverage, 0.01) << n;
  }
}

}  // namespace
}  // namespace keel::inspect
