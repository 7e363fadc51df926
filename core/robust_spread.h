// Median and median absolute deviation of a sample: location and scale that a few gross
// outliers (a feature on an object's flank, a DVL beam on fouling) do not move.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace keel {

struct RobustSpread {
  double median = 0.0;  // exact: the mean of the two middle values for an even count
  // 1.4826 median |x - median|: the standard deviation for Gaussian data, since the median of
  // |x - mu| for x ~ N(mu, sigma^2) is sigma / 1.4826 (1.4826 = 1 / Phi^-1(3/4)).
  double sigma = 0.0;
};

// Exact median; `values` is reordered. 0 for none.
inline double median_of(std::vector<double>& values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  double median = values[mid];
  if (values.size() % 2 == 0)
    median = 0.5 * (median + *std::max_element(values.begin(), values.begin() + mid));
  return median;
}

// {0, 0} for no values.
inline RobustSpread robust_spread(std::vector<double> values) {
  RobustSpread out;
  out.median = median_of(values);
  for (double& x : values) x = std::abs(x - out.median);
  out.sigma = 1.4826 * median_of(values);
  return out;
}

}  // namespace keel
