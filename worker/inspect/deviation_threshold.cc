#include "worker/inspect/deviation_threshold.h"

#include <algorithm>
#include <cmath>

namespace keel::inspect {

double robust_deviation_sigma(const std::vector<Landmark>& landmarks) {
  std::vector<double> magnitude;
  for (const Landmark& l : landmarks)
    if (l.lambda == 1) magnitude.push_back(std::abs(l.h_m));
  if (magnitude.empty()) return 0.0;
  const size_t mid = magnitude.size() / 2;
  std::nth_element(magnitude.begin(), magnitude.begin() + mid, magnitude.end());
  double median = magnitude[mid];
  if (magnitude.size() % 2 == 0)  // even count: mean of the two middle values
    median = 0.5 * (median + *std::max_element(magnitude.begin(), magnitude.begin() + mid));
  // 1.4826 = 1 / Phi^-1(3/4): the median of |x| for x ~ N(0, sigma^2) is sigma / 1.4826.
  return 1.4826 * median;
}

DeviationThreshold deviation_threshold(const std::vector<Landmark>& landmarks,
                                       const InspectOptions& options) {
  DeviationThreshold out;
  out.noise_sigma_m = robust_deviation_sigma(landmarks);
  out.tau_m = std::max(options.tau_m, options.tau_noise_sigmas * out.noise_sigma_m);
  return out;
}

}  // namespace keel::inspect
