#include "worker/inspect/top_sampling.h"

#include <algorithm>
#include <functional>

namespace keel::inspect {

double top_sampling_sigma(std::vector<double> abs_heights_m, const TopSampling& sampling) {
  if (abs_heights_m.empty() || sampling.spacings < 1) return 0.0;
  std::sort(abs_heights_m.begin(), abs_heights_m.end(), std::greater<>());
  // Site tops, highest first, until spacings + 1 are known.
  std::vector<double> sites = {abs_heights_m.front()};
  for (const double h : abs_heights_m) {
    if (static_cast<int>(sites.size()) > sampling.spacings) break;
    if (sites.back() - h > sampling.resolution_m) sites.push_back(h);
  }
  const int k = static_cast<int>(sites.size()) - 1;
  return k > 0 ? (sites.front() - sites.back()) / k : 0.0;
}

}  // namespace keel::inspect
