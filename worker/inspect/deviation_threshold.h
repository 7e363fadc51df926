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

// h over the landmarks the BA labelled on the model (lambda = 1): its median (the offset of the
// reconstruction from the model, e.g. x_gM pulled by features on an object's flanks that the
// max-mixture still labels on the model) and a robust sigma about that median. Measured about
// the median rather than about h = 0 so that an offset is not taken for noise: on keel-sim
// hauv-hull with 30 fouling patches the offset was -1.0 to -1.3 mm and the MAD about 0 was
// 1.3-1.5x the MAD about the median.
struct DeviationNoise {
  double bias_m = 0.0;   // median h
  double sigma_m = 0.0;  // 1.4826 median |h - bias|; 0 when no landmark has lambda = 1
};

struct DeviationThreshold {
  double noise_sigma_m = 0.0;  // DeviationNoise::sigma_m
  double bias_m = 0.0;         // DeviationNoise::bias_m
  // max(options.tau_m, |bias| + options.tau_noise_sigmas * noise_sigma) (options.tau_m alone
  // when tau_noise_sigmas is 0): clean hull sits at h = bias +- noise, so tau clears the noise
  // on either side of the offset.
  double tau_m = 0.0;
};

DeviationNoise robust_deviation_noise(const std::vector<Landmark>& landmarks);

DeviationThreshold deviation_threshold(const std::vector<Landmark>& landmarks,
                                       const InspectOptions& options);

}  // namespace keel::inspect
