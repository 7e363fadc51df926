// The threshold tau of line 6 of Algorithm 1 (seed 001): features with |h| > tau are clustered.
// Section 4.2.2 prefers tau = 0 (Fig. 21(b)) and raises it where false positives matter
// (0.06 m, Fig. 21(c)). Neither suits every reconstruction: at tau = 0 the bundle-adjusted noise
// of h on clean hull (millimetres with exact tracks, more with a SIFT frontend) clusters into
// shapes, and at 0.06 m a biofouling bump 5-8 cm high, whose features mostly sit on its flanks
// (h of 1-3 cm), is never clustered. So tau is raised above the noise of h as measured on the
// reconstruction itself: a robust standard deviation of h over the features the BA labelled on
// the model (lambda = 1, Eq. 7), times a number of sigmas.
#pragma once

#include <vector>

#include "worker/inspect/inspect_input.h"
#include "worker/inspect/inspect_options.h"

namespace keel::inspect {

struct DeviationThreshold {
  double noise_sigma_m = 0.0;  // 1.4826 median |h| over lambda = 1 (MAD about h = 0)
  double tau_m = 0.0;          // max(options.tau_m, options.tau_noise_sigmas * noise_sigma_m)
};

// 1.4826 median |h| over the landmarks with lambda = 1; 0 when there are none.
double robust_deviation_sigma(const std::vector<Landmark>& landmarks);

DeviationThreshold deviation_threshold(const std::vector<Landmark>& landmarks,
                                       const InspectOptions& options);

}  // namespace keel::inspect
