// The noise floor of tau (line 6 of Algorithm 1, seed 001): the median and a robust sigma of h
// over on-model features, checked against the Gaussian the features were drawn from and exact
// medians.
#include "worker/inspect/deviation_threshold.h"

#include <gtest/gtest.h>

#include <random>

namespace keel::inspect {
namespace {

Landmark feature(double h_m, int lambda) {
  Landmark l;
  l.h_m = h_m;
  l.lambda = lambda;
  return l;
}

std::vector<Landmark> gaussian_hull(int n, double sigma_m, uint32_t seed, double bias_m = 0.0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(bias_m, sigma_m);
  std::vector<Landmark> out;
  for (int i = 0; i < n; ++i) out.push_back(feature(normal(rng), 1));
  return out;
}

TEST(DeviationThreshold, RobustSigmaMatchesTheGaussianItWasDrawnFrom) {
  const double sigma = 0.004;
  const std::vector<Landmark> hull = gaussian_hull(40000, sigma, 7);
  // Standard error of the MAD estimate at n = 40000 is ~0.4 %.
  EXPECT_NEAR(robust_deviation_noise(hull).sigma_m, sigma, 0.02 * sigma);
  EXPECT_NEAR(robust_deviation_noise(hull).bias_m, 0.0, 0.02 * sigma);
  const DeviationThreshold t = deviation_threshold(hull, InspectOptions{});
  EXPECT_DOUBLE_EQ(t.tau_m,
                   std::abs(t.bias_m) + InspectOptions{}.tau_noise_sigmas * t.noise_sigma_m);
}

TEST(DeviationThreshold, AnOffsetIsMeasuredAsSuchNotAsNoiseAndTauClearsIt) {
  const double sigma = 0.002, bias = -0.0015;
  const std::vector<Landmark> hull = gaussian_hull(40000, sigma, 5, bias);
  const DeviationNoise noise = robust_deviation_noise(hull);
  EXPECT_NEAR(noise.bias_m, bias, 0.02 * sigma);
  EXPECT_NEAR(noise.sigma_m, sigma, 0.02 * sigma);  // about 0 it would read ~1.2 sigma
  const DeviationThreshold t = deviation_threshold(hull, InspectOptions{});
  EXPECT_NEAR(t.tau_m, 0.0015 + 8.0 * sigma, 0.2 * sigma);
  // A clean-hull feature on the offset's side clears tau by the same 8 sigma as without one.
  size_t beyond = 0;
  for (const Landmark& l : hull) beyond += std::abs(l.h_m) > t.tau_m;
  EXPECT_EQ(beyond, 0u);
}

TEST(DeviationThreshold, OffModelFeaturesAndOnModelOutliersBarelyMoveIt) {
  const double sigma = 0.004;
  std::vector<Landmark> hull = gaussian_hull(20000, sigma, 11);
  const double clean = robust_deviation_noise(hull).sigma_m;
  for (int i = 0; i < 10000; ++i) hull.push_back(feature(0.11, 0));  // an object, lambda = 0
  EXPECT_DOUBLE_EQ(robust_deviation_noise(hull).sigma_m, clean);
  for (int i = 0; i < 1000; ++i) hull.push_back(feature(0.04, 1));  // 5 % on-model outliers
  const double with_outliers = robust_deviation_noise(hull).sigma_m;
  EXPECT_GT(with_outliers, clean);
  EXPECT_LT(with_outliers, 1.1 * clean);  // a standard deviation would grow ~3x
}

TEST(DeviationThreshold, ExactMedianOfOddAndEvenCounts) {
  std::vector<Landmark> f = {feature(-0.003, 1), feature(0.001, 1), feature(0.002, 1),
                             feature(0.5, 0)};
  // h = -3, 1, 2 mm: median 1 mm, |h - 1 mm| = 4, 0, 1 mm.
  EXPECT_DOUBLE_EQ(robust_deviation_noise(f).bias_m, 0.001);
  EXPECT_DOUBLE_EQ(robust_deviation_noise(f).sigma_m, 1.4826 * 0.001);
  f.push_back(feature(0.004, 1));
  // h = -3, 1, 2, 4 mm: median 1.5 mm, |h - 1.5 mm| = 4.5, 0.5, 0.5, 2.5 mm -> 1.5 mm.
  EXPECT_DOUBLE_EQ(robust_deviation_noise(f).bias_m, 0.0015);
  EXPECT_NEAR(robust_deviation_noise(f).sigma_m, 1.4826 * 0.0015, 1e-15);
}

TEST(DeviationThreshold, FixedTauIsAFloorAndNoOnModelFeatureLeavesIt) {
  InspectOptions options;
  options.tau_m = 0.06;
  const std::vector<Landmark> hull = gaussian_hull(1000, 0.002, 3);
  EXPECT_DOUBLE_EQ(deviation_threshold(hull, options).tau_m, 0.06);  // 5 x 2 mm < 6 cm
  options.tau_m = 0.0;
  const std::vector<Landmark> off = {feature(0.2, 0), feature(0.3, 0)};
  const DeviationThreshold t = deviation_threshold(off, options);
  EXPECT_EQ(t.noise_sigma_m, 0.0);
  EXPECT_EQ(t.bias_m, 0.0);
  EXPECT_EQ(t.tau_m, 0.0);
  options.tau_noise_sigmas = 0.0;  // the paper's fixed tau
  EXPECT_EQ(deviation_threshold(hull, options).tau_m, 0.0);
}

}  // namespace
}  // namespace keel::inspect
