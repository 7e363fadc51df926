#include "worker/inspect/deviation_threshold.h"

#include <algorithm>
#include <cmath>

namespace keel::inspect {
namespace {

// Exact median (mean of the two middle values for an even count); values is reordered.
double median_of(std::vector<double>& values) {
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  double median = values[mid];
  if (values.size() % 2 == 0)
    median = 0.5 * (median + *std::max_element(values.begin(), values.begin() + mid));
  return median;
}

}  // namespace

DeviationNoise robust_deviation_noise(const std::vector<Landmark>& landmarks) {
  std::vector<double> h;
  for (const Landmark& l : landmarks)
    if (l.lambda == 1) h.push_back(l.h_m);
  if (h.empty()) return {};
  DeviationNoise out;
  out.bias_m = median_of(h);
  for (double& x : h) x = std::abs(x - out.bias_m);
  // 1.4826 = 1 / Phi^-1(3/4): the median of |x - mu| for x ~ N(mu, sigma^2) is sigma / 1.4826.
  out.sigma_m = 1.4826 * median_of(h);
  return out;
}

DeviationThreshold deviation_threshold(const std::vector<Landmark>& landmarks,
                                       const InspectOptions& options) {
  DeviationThreshold out;
  const DeviationNoise noise = robust_deviation_noise(landmarks);
  out.noise_sigma_m = noise.sigma_m;
  out.bias_m = noise.bias_m;
  // tau_noise_sigmas = 0 asks for the paper's fixed tau: no floor at all, offset included.
  const double floor_m = options.tau_noise_sigmas > 0.0
                             ? std::abs(noise.bias_m) + options.tau_noise_sigmas * noise.sigma_m
                             : 0.0;
  out.tau_m = std::max(options.tau_m, floor_m);
  return out;
}

}  // namespace keel::inspect
