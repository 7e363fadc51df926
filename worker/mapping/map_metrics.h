// Map quality metrics of seed 000 Sec. VI-C (Table V), per point over the neighbourhood
// V_k^N = the N map points within r of v_k (v_k itself included), r = 0.25 m by default:
//   surface density = N / (pi r^2)                                              Eq. (23)
//   roughness       = distance of v_k to the least-squares plane of its         Eq. (24)
//                     neighbours, v_k excluded (as CloudCompare's roughness; needs 3 others)
//   planarity       = (l2 - l3) / l1, l1 >= l2 >= l3 the eigenvalues of          Eq. (25)
//                     Sigma_k = 1/N sum (v_n - v_bar)(v_n - v_bar)^T about v_bar = med(v_n)  Eq.
//                     (26)
// v_bar is the exact medoid the paper names (the member minimising the summed distance to the
// others), found by the bounded search of medoid.h in ~3 O(N) passes instead of O(N^2).
// Neighbour search: cells of side r (cell_grid.h); the 3 x 3 x 3 block of a cell is gathered once
// for all its queries and its candidates within r selected with AVX2 where the CPU has it;
// cells are shared out dynamically over `threads`. Moments are centred and summed in double
// (a near-collinear neighbourhood's plane depends on products that float sums lose).
#pragma once

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <vector>

#include "core/point_cloud.h"

namespace keel::mapping {

struct MapMetricsOptions {
  double radius_m = 0.25;  // Table V
  int threads = 2;
  // 0: every point is a query point. Otherwise at most this many, evenly strided over the map
  // (neighbours always come from the whole map), to bound report time on huge maps.
  size_t max_query_points = 0;
  int histogram_bins = 20;
  // Called once per grid cell (side radius_m, at most kMaxMetricsRadiusM) holding query
  // points, from the metrics threads (so it must be thread-safe); it may throw to stop the
  // computation, which rethrows it: the stage passes its cancel check.
  std::function<void()> check_canceled;
};
// Largest radius accepted: Table V uses 0.25 m; a wider neighbourhood measures the structure's
// shape rather than its surface, and the work grows with r^2 per point (r = 1e9 m made every
// point a neighbour of every other).
inline constexpr double kMaxMetricsRadiusM = 1.0;

// Per query point; NaN where a metric is undefined (roughness with < 3 other neighbours,
// planarity with a degenerate neighbourhood).
struct PointMetrics {
  std::vector<size_t> query_index;  // into the map
  std::vector<float> surface_density;
  std::vector<float> roughness;
  std::vector<float> planarity;
};

struct Distribution {
  size_t count = 0;      // defined values
  size_t undefined = 0;  // NaN values left out
  double mean = 0.0, std = 0.0, min = 0.0, max = 0.0;
  double p05 = 0.0, p25 = 0.0, median = 0.0, p75 = 0.0, p95 = 0.0;  // linear interpolation
  std::vector<double> histogram_edges;  // bins + 1 edges from min to max
  std::vector<size_t> histogram_counts;
};

struct MapMetrics {
  size_t points = 0;
  size_t query_points = 0;
  double radius_m = 0.0;
  Distribution surface_density;  // points / m^2
  Distribution roughness;        // m
  Distribution planarity;        // [0, 1]
};

// Throws std::invalid_argument for a non-positive radius or non-finite points.
PointMetrics compute_point_metrics(const std::vector<Eigen::Vector3f>& points,
                                   const MapMetricsOptions& options = {});
// The same for the given query points only (indices into `points`, ascending); every point is
// a neighbour (a tile's points and its halo, with the tile's queries). max_query_points is
// ignored.
PointMetrics compute_point_metrics_at(const std::vector<Eigen::Vector3f>& points,
                                      const std::vector<size_t>& queries,
                                      const MapMetricsOptions& options = {});
Distribution summarize(const std::vector<float>& values, int histogram_bins);
MapMetrics compute_map_metrics(const PointCloud& map, const MapMetricsOptions& options = {});

nlohmann::json to_json(const Distribution& distribution);
nlohmann::json to_json(const MapMetrics& metrics);

}  // namespace keel::mapping
