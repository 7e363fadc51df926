#include "worker/compare/c2c_distance.h"

#include <stdexcept>
#include <string>

#include "core/parallel_for.h"

namespace keel::compare {
namespace {

template <class Index>  // NearestIndex or PointGrid: both find the nearest point exactly
std::vector<float> distances(const Index& reference, const std::vector<Eigen::Vector3f>& compared,
                             int threads) {
  for (size_t i = 0; i < compared.size(); ++i)
    if (!compared[i].allFinite())
      throw std::invalid_argument("C2C: compared point " + std::to_string(i) + " is not finite");
  std::vector<float> out(compared.size());
  keel::parallel_for(compared.size(), threads, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i)
      out[i] = static_cast<float>(reference.nearest(compared[i]).distance_m);
  });
  return out;
}

}  // namespace

std::vector<float> c2c_distances(const NearestIndex& reference,
                                 const std::vector<Eigen::Vector3f>& compared, int threads) {
  return distances(reference, compared, threads);
}

std::vector<float> c2c_distances(const PointGrid& reference, const PointGrid& compared,
                                 int threads) {
  const std::vector<float> in_cell_order = distances(reference, compared.points(), threads);
  std::vector<float> out(in_cell_order.size());
  for (size_t i = 0; i < out.size(); ++i) out[compared.input_index()[i]] = in_cell_order[i];
  return out;
}

}  // namespace keel::compare
