#include "worker/mapping/map_metrics.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "worker/mapping/cell_grid.h"
#include "worker/mapping/medoid.h"

namespace keel::mapping {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kUndefined = std::numeric_limits<float>::quiet_NaN();
constexpr uint32_t kNotQueried = 0xffffffffu;

struct NeighbourhoodMetrics {
  float roughness = kUndefined;
  float planarity = kUndefined;
};

// Scratch of one thread, reused across its cells and queries.
struct Scratch {
  std::vector<uint32_t> block;    // cells of the 3 x 3 x 3 block
  std::vector<float> cx, cy, cz;  // the block's points (candidates), absolute
  std::vector<float> nx, ny, nz;  // one query's neighbours, relative to the query point
  MedoidScratch medoid;
};

// Roughness and planarity of one neighbourhood given as offsets from the query point q (q's own
// offset, zero, included): q then adds nothing to the sums.
NeighbourhoodMetrics neighbourhood_metrics(Scratch& scratch, size_t n) {
  const Eigen::Index count = static_cast<Eigen::Index>(n);
  const Eigen::Map<const Eigen::ArrayXf> x(scratch.nx.data(), count), y(scratch.ny.data(), count),
      z(scratch.nz.data(), count);
  const Eigen::Vector3d sum(x.sum(), y.sum(), z.sum());
  Eigen::Matrix3d sum_outer;
  const double xx = (x * x).sum(), xy = (x * y).sum(), xz = (x * z).sum(), yy = (y * y).sum(),
               yz = (y * z).sum(), zz = (z * z).sum();
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

  // Eq. (26) about the exact medoid, Eq. (25) from its eigenvalues.
  if (n >= 3) {
    const size_t m =
        exact_medoid(scratch.nx.data(), scratch.ny.data(), scratch.nz.data(), n, &scratch.medoid)
            .index;
    const Eigen::Vector3d medoid(scratch.nx[m], scratch.ny[m], scratch.nz[m]);
    const Eigen::Vector3d mean = sum / static_cast<double>(n);
    // 1/N sum (v - m)(v - m)^T = S2/N - mean m^T - m mean^T + m m^T.
    const Eigen::Matrix3d sigma = sum_outer / static_cast<double>(n) - mean * medoid.transpose() -
                                  medoid * mean.transpose() + medoid * medoid.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(sigma, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d lambda = solver.eigenvalues();  // ascending: l3, l2, l1
    if (lambda[2] > 0.0) {
      out.planarity = static_cast<float>(std::clamp((lambda[1] - lambda[0]) / lambda[2], 0.0, 1.0));
    }
  }
  return out;
}

// Copies the points of the cells in scratch.block into the candidate columns.
void gather_block(const CellGrid& grid, Scratch& scratch) {
  size_t total = 0;
  for (const uint32_t c : scratch.block) total += grid.end(c) - grid.begin(c);
  for (auto* column :
       {&scratch.cx, &scratch.cy, &scratch.cz, &scratch.nx, &scratch.ny, &scratch.nz})
    column->resize(total);
  size_t at = 0;
  for (const uint32_t c : scratch.block) {
    const uint32_t b = grid.begin(c), e = grid.end(c);
    std::copy(grid.x().begin() + b, grid.x().begin() + e, scratch.cx.begin() + at);
    std::copy(grid.y().begin() + b, grid.y().begin() + e, scratch.cy.begin() + at);
    std::copy(grid.z().begin() + b, grid.z().begin() + e, scratch.cz.begin() + at);
    at += e - b;
  }
}

// Offsets from q of the candidates within r of q, written branch-free to the neighbour
// columns; returns their number.
size_t select_neighbours(float qx, float qy, float qz, float squared_radius, Scratch& s) {
  const size_t candidates = s.cx.size();
  const float* cx = s.cx.data();
  const float* cy = s.cy.data();
  const float* cz = s.cz.data();
  float* nx = s.nx.data();
  float* ny = s.ny.data();
  float* nz = s.nz.data();
  size_t n = 0;
  for (size_t i = 0; i < candidates; ++i) {
    const float dx = cx[i] - qx, dy = cy[i] - qy, dz = cz[i] - qz;
    nx[n] = dx;
    ny[n] = dy;
    nz[n] = dz;
    n += static_cast<size_t>(dx * dx + dy * dy + dz * dz < squared_radius);
  }
  return n;
}

// Runs body(worker, cell) for every cell on `threads` threads pulling batches of cells from a
// shared counter (map density varies, so equal static shares would leave a core idle).
template <typename Body>  // Body: void(size_t worker, size_t cell)
void for_each_cell(size_t cells, int threads, const Body& body) {
  constexpr size_t kBatch = 16;
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto run = [&](size_t worker) {
    try {
      for (size_t b = next.fetch_add(kBatch); b < cells; b = next.fetch_add(kBatch)) {
        for (size_t c = b; c < std::min(cells, b + kBatch); ++c) body(worker, c);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = cells;
    }
  };
  const size_t workers = std::min<size_t>(std::max(threads, 1), (cells + kBatch - 1) / kBatch);
  std::vector<std::thread> pool;
  for (size_t w = 1; w < workers; ++w) pool.emplace_back(run, w);
  run(0);
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
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

  // Cells of side r: every neighbour of a point of cell c lies in the 3 x 3 x 3 block around
  // c, gathered once for all of c's queries.
  const CellGrid grid(points, options.radius_m);
  std::vector<uint32_t> query_of_point;  // input index -> query number; empty: the identity
  if (queries != points.size()) {
    query_of_point.assign(points.size(), kNotQueried);
    for (size_t q = 0; q < queries; ++q)
      query_of_point[out.query_index[q]] = static_cast<uint32_t>(q);
  }
  const double area = kPi * options.radius_m * options.radius_m;
  const float squared_radius = static_cast<float>(options.radius_m * options.radius_m);
  const int threads = queries < 1024 ? 1 : options.threads;
  std::vector<Scratch> scratches(static_cast<size_t>(std::max(threads, 1)));
  for_each_cell(grid.cell_count(), threads, [&](size_t worker, size_t c) {
    Scratch* s = &scratches[worker];
    bool any_query = query_of_point.empty();
    for (uint32_t i = grid.begin(c); !any_query && i < grid.end(c); ++i) {
      any_query = query_of_point[grid.input_index()[i]] != kNotQueried;
    }
    if (!any_query) return;
    grid.block_around(c, &s->block);
    gather_block(grid, *s);
    for (uint32_t i = grid.begin(c); i < grid.end(c); ++i) {
      const uint32_t input = grid.input_index()[i];
      const uint32_t q = query_of_point.empty() ? input : query_of_point[input];
      if (q == kNotQueried) continue;
      const size_t n = select_neighbours(grid.x()[i], grid.y()[i], grid.z()[i], squared_radius, *s);
      out.surface_density[q] = static_cast<float>(n / area);  // Eq. (23)
      const NeighbourhoodMetrics metrics = neighbourhood_metrics(*s, n);
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
