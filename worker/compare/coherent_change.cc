#include "worker/compare/coherent_change.h"

#include <cmath>
#include <stdexcept>

#include "core/parallel_for.h"
#include "worker/compare/nearest_index.h"

namespace keel::compare {

void require_coherent_change(std::vector<CoreChange>* cores, double radius_m, int threads) {
  if (!(radius_m >= 0) || !std::isfinite(radius_m))
    throw std::invalid_argument("significance radius: expected a length >= 0");
  if (radius_m == 0) return;
  std::vector<Eigen::Vector3f> positions;
  std::vector<uint32_t> defined;
  for (size_t i = 0; i < cores->size(); ++i)
    if ((*cores)[i].defined()) positions.push_back((*cores)[i].position), defined.push_back(i);
  if (positions.empty()) return;
  const NearestIndex index(positions);
  // Each core's sign of significant change: +1, -1, or 0 when not significant.
  std::vector<int> sign(defined.size());
  for (size_t k = 0; k < defined.size(); ++k) {
    const CoreChange& c = (*cores)[defined[k]];
    sign[k] = c.significant ? (c.distance_m > 0 ? 1 : -1) : 0;
  }
  std::vector<char> keep(defined.size(), 0);
  keel::parallel_for(defined.size(), threads, [&](size_t begin, size_t end) {
    std::vector<uint32_t> near;
    for (size_t k = begin; k < end; ++k) {
      if (sign[k] == 0) continue;
      index.within(positions[k], radius_m, &near);
      size_t agree = 0;
      for (uint32_t j : near) agree += sign[j] == sign[k];
      keep[k] = 2 * agree >= near.size();
    }
  });
  for (size_t k = 0; k < defined.size(); ++k) (*cores)[defined[k]].significant = keep[k];
}

}  // namespace keel::compare
