// ROR and DROR of Table III, seed 000, on a kd-tree (RadiusSearch), parallel over `threads`.
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "worker/mapping/cloud_ops.h"
#include "worker/mapping/filters.h"
#include "core/parallel_for.h"
#include "worker/mapping/radius_search.h"

namespace keel::mapping {
namespace {

constexpr double kPi = 3.14159265358979323846;

void check_positive(double value, const char* what) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw std::invalid_argument(std::string(what) + ": expected a positive number, got " +
                                std::to_string(value));
  }
}

}  // namespace

double dror_search_radius(const DrorFilter& filter, double r_xy_m) {
  const double alpha_rad = filter.alpha_deg * kPi / 180.0;
  return std::max(filter.beta * alpha_rad * r_xy_m, filter.sr_min_m);
}

std::vector<uint8_t> radius_outlier_keep(const RadiusOutlierFilter& filter,
                                         const std::vector<Eigen::Vector3f>& points, int threads) {
  check_positive(filter.radius_m, "ror.radius");
  if (filter.min_neighbors < 0) throw std::invalid_argument("ror.min_neighbors: expected >= 0");
  if (points.empty() || filter.min_neighbors == 0) return std::vector<uint8_t>(points.size(), 1);
  const RadiusSearch search(points);
  // The count includes the point itself, hence min_neighbors + 1 (PCL's k = min_pts + 1).
  const int needed = filter.min_neighbors + 1;
  std::vector<uint8_t> keep(points.size());
  const std::vector<uint32_t>& order = search.spatial_order();  // cache-friendly query order
  parallel_for(points.size(), threads, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      keep[order[i]] = search.count_around(i, filter.radius_m, needed) >= needed;
    }
  });
  return keep;
}

size_t apply_radius_outlier(const RadiusOutlierFilter& filter, PointCloud& cloud, int threads) {
  return keep_points(cloud, radius_outlier_keep(filter, cloud.xyz, threads));
}

std::vector<uint8_t> dror_keep(const DrorFilter& filter, const std::vector<Eigen::Vector3f>& points,
                               int threads) {
  check_positive(filter.beta, "dror.beta");
  check_positive(filter.alpha_deg, "dror.alpha");
  check_positive(filter.sr_min_m, "dror.sr_min");
  if (filter.k_min < 0) throw std::invalid_argument("dror.k_min: expected >= 0");
  // Every point counts itself.
  if (points.empty() || filter.k_min <= 1) return std::vector<uint8_t>(points.size(), 1);
  const RadiusSearch search(points);
  std::vector<uint8_t> keep(points.size());
  const std::vector<uint32_t>& order = search.spatial_order();
  parallel_for(points.size(), threads, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const uint32_t n = order[i];
      const Eigen::Vector3f& p = points[n];
      // sqrt of the (exact) double squares rather than std::hypot: hypot was 8 % of DROR's time;
      // the two differ by at most an ulp (the tests' ambiguity margin is 1e-5 m).
      const double x = p.x(), y = p.y();
      const double r_xy = std::sqrt(x * x + y * y);
      const double radius = dror_search_radius(filter, r_xy);
      keep[n] = search.count_around(i, radius, filter.k_min) >= filter.k_min;
    }
  });
  return keep;
}

size_t apply_dror(const DrorFilter& filter, PointCloud& cloud, int threads) {
  return keep_points(cloud, dror_keep(filter, cloud.xyz, threads));
}

}  // namespace keel::mapping
