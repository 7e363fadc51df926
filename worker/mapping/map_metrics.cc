#include "worker/mapping/map_metrics.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "worker/mapping/parallel_for.h"
#include "worker/mapping/radius_search.h"
#include "worker/mapping/selection.h"

namespace keel::mapping {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kUndefined = std::numeric_limits<float>::quiet_NaN();

struct NeighbourhoodMetrics {
  float roughness = kUndefined;
  float planarity = kUndefined;
};

// Scratch for one neighbourhood, reused across the queries of a thread.
struct Scratch {
  std::vector<Eigen::Vector3f> neighbours;
  std::vector<float> axis[3];
};

// Coordinates are taken relative to the query point q, so q contributes zero to the sums.
NeighbourhoodMetrics neighbourhood_metrics(const Eigen::Vector3f& q, Scratch& scratch) {
  const size_t n = scratch.neighbours.size();  // includes q itself
  double s[3] = {0, 0, 0};
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  for (int a = 0; a < 3; ++a) scratch.axis[a].resize(n);
  for (size_t m = 0; m < n; ++m) {
    const Eigen::Vector3f d = scratch.neighbours[m] - q;
    const double x = d.x(), y = d.y(), z = d.z();
    s[0] += x;
    s[1] += y;
    s[2] += z;
    xx += x * x;
    xy += x * y;
    xz += x * z;
    yy += y * y;
    yz += y * z;
    zz += z * z;
    scratch.axis[0][m] = d.x();
    scratch.axis[1][m] = d.y();
    scratch.axis[2][m] = d.z();
  }
  const Eigen::Vector3d sum(s[0], s[1], s[2]);
  Eigen::Matrix3d sum_outer;
  sum_outer << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  NeighbourhoodMetrics out;

  // Eq. (24): plane through the centroid of the n - 1 others (q adds nothing to the sums).
  if (n >= 4) {
    const double others = static_cast<double>(n - 1);
    const Eigen::Vector3d centroid = sum / others;
    const Eigen::Matrix3d covariance = sum_outer / others - centroid * centroid.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(covariance);
    const Eigen::Vector3d normal = solver.eigenvectors().col(0);         // smallest eigenvalue
    out.roughness = static_cast<float>(std::abs(normal.dot(centroid)));  // |n . (q - c)|
  }

  // Eq. (26) about the coordinate-wise median, Eq. (25) from its eigenvalues.
  if (n >= 3) {
    Eigen::Vector3d median;
    for (int a = 0; a < 3; ++a) median[a] = select_kth(scratch.axis[a].data(), n, n / 2);
    const double count = static_cast<double>(n);
    const Eigen::Vector3d mean = sum / count;
    // 1/N sum (v - m)(v - m)^T = S2/N - mean m^T - m mean^T + m m^T.
    const Eigen::Matrix3d sigma = sum_outer / count - mean * median.transpose() -
                                  median * mean.transpose() + median * median.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(sigma, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d lambda = solver.eigenvalues();  // ascending: l3, l2, l1
    if (lambda[2] > 0.0) {
      out.planarity = static_cast<float>(std::clamp((lambda[1] - lambda[0]) / lambda[2], 0.0, 1.0));
    }
  }
  return out;
}

double quantile(const std::vector<double>& sorted, double p) {
  const double position = p * static_cast<double>(sorted.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(position));
  const size_t above = std::min(below + 1, sorted.size() - 1);
  const double fraction = position - static_cast<double>(below);
  return sorted[below] + fraction * (sorted[above] - sorted[below]);
}

}  // namespace

PointMetrics compute_point_metrics(const std::vector<Eigen::Vector3f>& points,
                                   const MapMetricsOptions& options) {
  if (!std::isfinite(options.radius_m) || options.radius_m <= 0.0) {
    throw std::invalid_argument("map metrics: radius must be positive, got " +
                                std::to_string(options.radius_m));
  }
  for (size_t k = 0; k < points.size(); ++k) {
    if (!points[k].allFinite()) {
      throw std::invalid_argument("map metrics: point " + std::to_string(k) + " is not finite");
    }
  }
  PointMetrics out;
  const size_t queries = options.max_query_points > 0
                             ? std::min(options.max_query_points, points.size())
                             : points.size();
  out.query_index.resize(queries);
  for (size_t q = 0; q < queries; ++q) out.query_index[q] = q * points.size() / queries;
  out.surface_density.assign(queries, kUndefined);
  out.roughness.assign(queries, kUndefined);
  out.planarity.assign(queries, kUndefined);
  if (queries == 0) return out;

  const RadiusSearch search(points);
  // Visit the queries in the search's Morton order: consecutive queries touch the same leaves.
  const std::vector<uint32_t>& order = search.spatial_order();
  std::vector<uint32_t> visit;  // query numbers q in Morton order of their points
  if (queries == points.size()) {
    visit = order;  // query q is point q
  } else {
    std::vector<uint32_t> rank(points.size());
    for (size_t i = 0; i < order.size(); ++i) rank[order[i]] = static_cast<uint32_t>(i);
    visit.resize(queries);
    for (size_t q = 0; q < queries; ++q) visit[q] = static_cast<uint32_t>(q);
    std::sort(visit.begin(), visit.end(), [&](uint32_t a, uint32_t b) {
      return rank[out.query_index[a]] < rank[out.query_index[b]];
    });
  }

  const double area = kPi * options.radius_m * options.radius_m;
  parallel_for(queries, options.threads, [&](size_t begin, size_t end) {
    Scratch scratch;
    for (size_t v = begin; v < end; ++v) {
      const size_t q = visit[v];
      const Eigen::Vector3f& p = points[out.query_index[q]];
      search.points_within(p, options.radius_m, &scratch.neighbours);
      out.surface_density[q] = static_cast<float>(scratch.neighbours.size() / area);  // Eq. (23)
      const NeighbourhoodMetrics metrics = neighbourhood_metrics(p, scratch);
      out.roughness[q] = metrics.roughness;
      out.planarity[q] = metrics.planarity;
    }
  });
  return out;
}

Distribution summarize(const std::vector<float>& values, int histogram_bins) {
  Distribution d;
  std::vector<double> sorted;
  sorted.reserve(values.size());
  for (const float v : values) {
    if (std::isnan(v)) {
      ++d.undefined;
    } else {
      sorted.push_back(v);
    }
  }
  d.count = sorted.size();
  if (sorted.empty()) return d;
  std::sort(sorted.begin(), sorted.end());
  double sum = 0.0;
  for (const double v : sorted) sum += v;
  d.mean = sum / static_cast<double>(d.count);
  double squares = 0.0;
  for (const double v : sorted) squares += (v - d.mean) * (v - d.mean);
  d.std = std::sqrt(squares / static_cast<double>(d.count));  // population, like numpy
  d.min = sorted.front();
  d.max = sorted.back();
  d.p05 = quantile(sorted, 0.05);
  d.p25 = quantile(sorted, 0.25);
  d.median = quantile(sorted, 0.5);
  d.p75 = quantile(sorted, 0.75);
  d.p95 = quantile(sorted, 0.95);
  const int bins = std::max(1, histogram_bins);
  const double width = (d.max - d.min) / bins;
  for (int b = 0; b <= bins; ++b) d.histogram_edges.push_back(d.min + b * width);
  d.histogram_counts.assign(static_cast<size_t>(bins), 0);
  for (const double v : sorted) {
    const int bin = width > 0.0 ? static_cast<int>((v - d.min) / width) : 0;
    ++d.histogram_counts[static_cast<size_t>(std::clamp(bin, 0, bins - 1))];
  }
  return d;
}

MapMetrics compute_map_metrics(const PointCloud& map, const MapMetricsOptions& options) {
  const PointMetrics per_point = compute_point_metrics(map.xyz, options);
  MapMetrics metrics;
  metrics.points = map.size();
  metrics.query_points = per_point.query_index.size();
  metrics.radius_m = options.radius_m;
  metrics.surface_density = summarize(per_point.surface_density, options.histogram_bins);
  metrics.roughness = summarize(per_point.roughness, options.histogram_bins);
  metrics.planarity = summarize(per_point.planarity, options.histogram_bins);
  return metrics;
}

nlohmann::json to_json(const Distribution& d) {
  return {{"count", d.count},
          {"undefined", d.undefined},
          {"mean", d.mean},
          {"std", d.std},
          {"min", d.min},
          {"p05", d.p05},
          {"p25", d.p25},
          {"median", d.median},
          {"p75", d.p75},
          {"p95", d.p95},
          {"max", d.max},
          {"histogram_edges", d.histogram_edges},
          {"histogram_counts", d.histogram_counts}};
}

nlohmann::json to_json(const MapMetrics& metrics) {
  return {{"points", metrics.points},
          {"query_points", metrics.query_points},
          {"radius_m", metrics.radius_m},
          {"surface_density_per_m2", to_json(metrics.surface_density)},
          {"roughness_m", to_json(metrics.roughness)},
          {"planarity", to_json(metrics.planarity)}};
}

}  // namespace keel::mapping
