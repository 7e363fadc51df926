// How far an object's top may lie beyond its highest feature: shapes.json's
// height_sampling_sigma_m, which `compare` uses for the uncertainty of a shape's growth.
//
// A shape's height is its largest |h| (shape_report.h). Features sit where the object has
// texture, so the top itself is seldom one of them. Near a dome's top the height falls off as
// the square of the distance from it, so for features spread evenly over the surface the
// heights just below the top are evenly spread too: the gap from the highest feature to the
// top is then one more spacing of the highest order statistics, exponentially distributed
// with their mean spacing as its mean and standard deviation. The mean of several spacings
// estimates it far better than the single gap to the second highest (Robson & Whitlock 1964,
// this field's earlier estimate), whose own scatter equals its mean.
//
// Features are not independent samples of the surface: a texture blob gives several features
// at nearly the same height. Heights within `resolution_m` of a higher one are one sampling
// site, counted once; inspect sets resolution_m to 3 deviation-noise sigmas, below which two
// heights cannot be told apart.
#pragma once

#include <vector>

namespace keel::inspect {

struct TopSampling {
  double resolution_m = 0.0;  // heights closer than this are one site
  int spacings = 4;           // the mean of this many spacings below the highest site
};

// The mean spacing of the highest sites of |h| (m): (s_0 - s_k) / k with k = min(spacings,
// number of sites - 1); 0 with a single site (every feature at one height).
double top_sampling_sigma(std::vector<double> abs_heights_m, const TopSampling& sampling);

}  // namespace keel::inspect
