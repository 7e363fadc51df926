#include "worker/inspect/deviation_threshold.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/robust_spread.h"

namespace keel::inspect {

DeviationNoise robust_deviation_noise(const std::vector<Landmark>& landmarks) {
  std::vector<double> h;
  for (const Landmark& l : landmarks)
    if (l.lambda == 1) h.push_back(l.h_m);
  const RobustSpread spread = robust_spread(std::move(h));
  return {spread.median, spread.sigma};
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
