#include "worker/mapping/map_metrics.h"

#include <Eigen/Eigenvalues>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define KEEL_METRICS_AVX2 1  // AVX2 neighbour selection chosen at run time when the CPU has it
#endif

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
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

// The neighbours' offsets v: their mean and scatter sum (v - mean)(v - mean)^T. Centred before
// squaring: raw second moments lose a near-collinear neighbourhood's small eigenvalues to
// float cancellation.
struct Moments {
  Eigen::Vector3d mean;
  Eigen::Matrix3d scatter;
};

#if defined(__SSE2__)
double horizontal_sum(__m128 v) {
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, v);
  return (double(lanes[0]) + lanes[1]) + (double(lanes[2]) + lanes[3]);
}
#endif

Eigen::Vector3d offset_sum(const float* x, const float* y, const float* z, size_t n) {
  double s[3] = {0, 0, 0};
  size_t k = 0;
#if defined(__SSE2__)
  __m128 sx = _mm_setzero_ps(), sy = _mm_setzero_ps(), sz = _mm_setzero_ps();
  for (; k + 4 <= n; k += 4) {
    sx = _mm_add_ps(sx, _mm_loadu_ps(x + k));
    sy = _mm_add_ps(sy, _mm_loadu_ps(y + k));
    sz = _mm_add_ps(sz, _mm_loadu_ps(z + k));
  }
  s[0] = horizontal_sum(sx), s[1] = horizontal_sum(sy), s[2] = horizontal_sum(sz);
#endif
  for (; k < n; ++k) s[0] += x[k], s[1] += y[k], s[2] += z[k];
  return Eigen::Vector3d(s[0], s[1], s[2]);
}

// sum (v - c)(v - c)^T: xx, yy, zz, xy, xz, yz, in double: a neighbourhood of three or four
// nearly collinear points (l2 ~ 1e-7 l1) defines its plane only through products that float
// sums round away.
void centred_products(const float* x, const float* y, const float* z, size_t n,
                      const Eigen::Vector3d& c, double* s) {
  size_t k = 0;
#if defined(__SSE2__)
  const __m128d cx = _mm_set1_pd(c.x()), cy = _mm_set1_pd(c.y()), cz = _mm_set1_pd(c.z());
  __m128d a[6];
  for (__m128d& lane : a) lane = _mm_setzero_pd();
  for (; k + 2 <= n; k += 2) {
    const __m128d dx = _mm_sub_pd(
        _mm_cvtps_pd(_mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(x + k)))), cx);
    const __m128d dy = _mm_sub_pd(
        _mm_cvtps_pd(_mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(y + k)))), cy);
    const __m128d dz = _mm_sub_pd(
        _mm_cvtps_pd(_mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(z + k)))), cz);
    a[0] = _mm_add_pd(a[0], _mm_mul_pd(dx, dx)), a[1] = _mm_add_pd(a[1], _mm_mul_pd(dy, dy));
    a[2] = _mm_add_pd(a[2], _mm_mul_pd(dz, dz)), a[3] = _mm_add_pd(a[3], _mm_mul_pd(dx, dy));
    a[4] = _mm_add_pd(a[4], _mm_mul_pd(dx, dz)), a[5] = _mm_add_pd(a[5], _mm_mul_pd(dy, dz));
  }
  for (int i = 0; i < 6; ++i) {
    alignas(16) double lanes[2];
    _mm_store_pd(lanes, a[i]);
    s[i] = lanes[0] + lanes[1];
  }
#endif
  for (; k < n; ++k) {
    const double dx = x[k] - c.x(), dy = y[k] - c.y(), dz = z[k] - c.z();
    s[0] += dx * dx, s[1] += dy * dy, s[2] += dz * dz;
    s[3] += dx * dy, s[4] += dx * dz, s[5] += dy * dz;
  }
}

Moments neighbourhood_moments(const float* x, const float* y, const float* z, size_t n) {
  Moments m;
  m.mean = offset_sum(x, y, z, n) / static_cast<double>(n);
  double s[6] = {0, 0, 0, 0, 0, 0};
  centred_products(x, y, z, n, m.mean, s);
  m.scatter << s[0], s[3], s[4], s[3], s[1], s[5], s[4], s[5], s[2];
  return m;
}

// Roughness and planarity of one neighbourhood given as offsets from the query point q (q's own
// offset, zero, included).
NeighbourhoodMetrics neighbourhood_metrics(Scratch& scratch, size_t n) {
  const Moments moments =
      neighbourhood_moments(scratch.nx.data(), scratch.ny.data(), scratch.nz.data(), n);
  const double count = static_cast<double>(n);
  NeighbourhoodMetrics out;

  // Eq. (24): plane through the centroid c of the n - 1 others. q = 0 adds nothing to the sum,
  // so c = n mean / (n - 1), and their scatter about c is the n members' scatter about c
  // (scatter + n (mean - c)(mean - c)^T) less q's term c c^T.
  if (n >= 4) {
    const double others = count - 1.0;
    const Eigen::Vector3d centroid = moments.mean * (count / others);
    const Eigen::Vector3d shift = moments.mean - centroid;
    const Eigen::Matrix3d covariance =
        (moments.scatter + count * shift * shift.transpose() - centroid * centroid.transpose()) /
        others;
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
    // 1/N sum (v - m)(v - m)^T = scatter / N + (mean - m)(mean - m)^T.
    const Eigen::Vector3d shift = moments.mean - medoid;
    const Eigen::Matrix3d sigma = moments.scatter / count + shift * shift.transpose();
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
  for (auto* column : {&scratch.cx, &scratch.cy, &scratch.cz}) column->resize(total);
  // Selection stores whole vectors at the running count: room for one past the last.
  for (auto* column : {&scratch.nx, &scratch.ny, &scratch.nz}) column->resize(total + 8);
  size_t at = 0;
  for (const uint32_t c : scratch.block) {
    const uint32_t b = grid.begin(c), e = grid.end(c);
    std::copy(grid.x().begin() + b, grid.x().begin() + e, scratch.cx.begin() + at);
    std::copy(grid.y().begin() + b, grid.y().begin() + e, scratch.cy.begin() + at);
    std::copy(grid.z().begin() + b, grid.z().begin() + e, scratch.cz.begin() + at);
    at += e - b;
  }
}

// Offsets from q of candidates [begin, candidates) within r of q, written branch-free to the
// neighbour columns from position n on; returns the new count.
size_t select_scalar(float qx, float qy, float qz, float squared_radius, const Scratch& s,
                     size_t begin, size_t n, float* nx, float* ny, float* nz) {
  const float* cx = s.cx.data();
  const float* cy = s.cy.data();
  const float* cz = s.cz.data();
  for (size_t i = begin; i < s.cx.size(); ++i) {
    const float dx = cx[i] - qx, dy = cy[i] - qy, dz = cz[i] - qz;
    nx[n] = dx;
    ny[n] = dy;
    nz[n] = dz;
    n += static_cast<size_t>(dx * dx + dy * dy + dz * dz < squared_radius);
  }
  return n;
}

#if defined(KEEL_METRICS_AVX2)
// For each 8-bit mask, the lanes whose bit is set, in order, then the rest: a permutation that
// packs the selected lanes to the front.
struct CompressTable {
  uint8_t lanes[256][8];
  CompressTable() {
    for (int mask = 0; mask < 256; ++mask) {
      int at = 0;
      for (int lane = 0; lane < 8; ++lane) {
        if (mask >> lane & 1) lanes[mask][at++] = static_cast<uint8_t>(lane);
      }
      for (int lane = 0; lane < 8; ++lane) {
        if (!(mask >> lane & 1)) lanes[mask][at++] = static_cast<uint8_t>(lane);
      }
    }
  }
};
const CompressTable kCompress;

// Eight candidates a step: the selected offsets packed to the front of a vector stored whole
// at the running count (the columns have 8 floats of slack). Same order and test as scalar.
__attribute__((target("avx2,popcnt"))) size_t select_avx2(float qx, float qy, float qz,
                                                          float squared_radius, Scratch& s) {
  const size_t candidates = s.cx.size();
  const float *cx = s.cx.data(), *cy = s.cy.data(), *cz = s.cz.data();
  float *nx = s.nx.data(), *ny = s.ny.data(), *nz = s.nz.data();
  const __m256 vx = _mm256_set1_ps(qx), vy = _mm256_set1_ps(qy), vz = _mm256_set1_ps(qz);
  const __m256 r2 = _mm256_set1_ps(squared_radius);
  size_t n = 0, i = 0;
  for (; i + 8 <= candidates; i += 8) {
    const __m256 dx = _mm256_sub_ps(_mm256_loadu_ps(cx + i), vx);
    const __m256 dy = _mm256_sub_ps(_mm256_loadu_ps(cy + i), vy);
    const __m256 dz = _mm256_sub_ps(_mm256_loadu_ps(cz + i), vz);
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                    _mm256_mul_ps(dz, dz));
    const int mask = _mm256_movemask_ps(_mm256_cmp_ps(d2, r2, _CMP_LT_OQ));
    if (mask == 0) continue;
    const __m256i order = _mm256_cvtepu8_epi32(
        _mm_loadl_epi64(reinterpret_cast<const __m128i*>(kCompress.lanes[mask])));
    _mm256_storeu_ps(nx + n, _mm256_permutevar8x32_ps(dx, order));
    _mm256_storeu_ps(ny + n, _mm256_permutevar8x32_ps(dy, order));
    _mm256_storeu_ps(nz + n, _mm256_permutevar8x32_ps(dz, order));
    n += static_cast<size_t>(__builtin_popcount(static_cast<unsigned>(mask)));
  }
  return select_scalar(qx, qy, qz, squared_radius, s, i, n, nx, ny, nz);
}

bool cpu_has_avx2() {
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
  return has;
}
#endif

// Offsets from q of the candidates within r of q, in the neighbour columns; returns their
// number.
size_t select_neighbours(float qx, float qy, float qz, float squared_radius, Scratch& s) {
#if defined(KEEL_METRICS_AVX2)
  if (cpu_has_avx2()) return select_avx2(qx, qy, qz, squared_radius, s);
#endif
  return select_scalar(qx, qy, qz, squared_radius, s, 0, 0, s.nx.data(), s.ny.data(), s.nz.data());
}

// The query reading input point `input` (kNotQueried if none) when query q reads point
// floor(q points / queries): q = ceil(input queries / points) is the first query reading a point
// at or after `input`. Arithmetic, not a table: a table indexed by input point is read in grid
// order, i.e. at random. Products stay below 2^64 (points < 2^32).
uint32_t query_of(uint64_t input, uint64_t points, uint64_t queries) {
  const uint64_t q = (input * queries + points - 1) / points;
  return q < queries && q * points / queries == input ? static_cast<uint32_t>(q) : kNotQueried;
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

// Quantile p of `values` (linear interpolation between the order statistics below and above
// p (n - 1), like numpy) for ascending p: `selected` ranks [0, selected) are already in place
// and no larger than the rest, so each selection only partitions what is left.
double quantile(std::vector<float>* values, double p, size_t* selected) {
  const size_t n = values->size();
  const double position = p * static_cast<double>(n - 1);
  const size_t below = static_cast<size_t>(std::floor(position));
  const size_t above = std::min(below + 1, n - 1);
  for (const size_t rank : {below, above}) {
    if (rank < *selected) continue;
    std::nth_element(values->begin() + static_cast<std::ptrdiff_t>(*selected),
                     values->begin() + static_cast<std::ptrdiff_t>(rank), values->end());
    *selected = rank + 1;
  }
  const double fraction = position - static_cast<double>(below);
  const double low = (*values)[below], high = (*values)[above];
  return low + fraction * (high - low);
}

}  // namespace

namespace {

void check_metrics_input(const std::vector<Eigen::Vector3f>& points,
                         const MapMetricsOptions& options) {
  if (!std::isfinite(options.radius_m) || options.radius_m <= 0.0 ||
      options.radius_m > kMaxMetricsRadiusM) {
    throw std::invalid_argument("map metrics: radius must lie in (0, " +
                                std::to_string(kMaxMetricsRadiusM) + "] m (Table V: 0.25), got " +
                                std::to_string(options.radius_m));
  }
  for (size_t k = 0; k < points.size(); ++k) {
    if (!points[k].allFinite()) {
      throw std::invalid_argument("map metrics: point " + std::to_string(k) + " is not finite");
    }
  }
}

// The metrics of out.query_index's points, `query_of(input)` giving the query reading input
// point `input` (kNotQueried if none).
template <typename QueryOf>
void compute_queries(const std::vector<Eigen::Vector3f>& points, const QueryOf& query_of,
                     const MapMetricsOptions& options, PointMetrics& out) {
  const size_t queries = out.query_index.size();
  out.surface_density.assign(queries, kUndefined);
  out.roughness.assign(queries, kUndefined);
  out.planarity.assign(queries, kUndefined);
  if (queries == 0) return;

  // Cells of side r: every neighbour of a point of cell c lies in the 3 x 3 x 3 block around
  // c, gathered once for all of c's queries.
  const CellGrid grid(points, options.radius_m);
  const double area = kPi * options.radius_m * options.radius_m;
  const float squared_radius = static_cast<float>(options.radius_m * options.radius_m);
  const int threads = queries < 1024 ? 1 : options.threads;
  std::vector<Scratch> scratches(static_cast<size_t>(std::max(threads, 1)));
  std::vector<CellGrid::BlockFinder> finders(scratches.size(), CellGrid::BlockFinder(grid));
  for_each_cell(grid.cell_count(), threads, [&](size_t worker, size_t c) {
    Scratch* s = &scratches[worker];
    bool any_query = false;
    for (uint32_t i = grid.begin(c); !any_query && i < grid.end(c); ++i) {
      any_query = query_of(grid.input_index()[i]) != kNotQueried;
    }
    if (!any_query) return;
    if (options.check_canceled) options.check_canceled();
    finders[worker].block_around(c, &s->block);
    gather_block(grid, *s);
    for (uint32_t i = grid.begin(c); i < grid.end(c); ++i) {
      const uint32_t input = grid.input_index()[i];
      const uint32_t q = query_of(input);
      if (q == kNotQueried) continue;
      const size_t n = select_neighbours(grid.x()[i], grid.y()[i], grid.z()[i], squared_radius, *s);
      out.surface_density[q] = static_cast<float>(n / area);  // Eq. (23)
      const NeighbourhoodMetrics metrics = neighbourhood_metrics(*s, n);
      out.roughness[q] = metrics.roughness;
      out.planarity[q] = metrics.planarity;
    }
  });
}

}  // namespace

PointMetrics compute_point_metrics(const std::vector<Eigen::Vector3f>& points,
                                   const MapMetricsOptions& options) {
  check_metrics_input(points, options);
  PointMetrics out;
  const size_t queries = options.max_query_points > 0
                             ? std::min(options.max_query_points, points.size())
                             : points.size();
  out.query_index.resize(queries);
  for (size_t q = 0; q < queries; ++q) out.query_index[q] = q * points.size() / queries;  // strided
  compute_queries(
      points, [&](uint64_t input) { return query_of(input, points.size(), queries); }, options,
      out);
  return out;
}

PointMetrics compute_point_metrics_at(const std::vector<Eigen::Vector3f>& points,
                                      const std::vector<size_t>& queries,
                                      const MapMetricsOptions& options) {
  check_metrics_input(points, options);
  std::vector<uint32_t> query_of_input(points.size(), kNotQueried);
  for (size_t q = 0; q < queries.size(); ++q) {
    if (queries[q] >= points.size() || (q > 0 && queries[q] <= queries[q - 1]))
      throw std::invalid_argument("map metrics: query indices must be ascending and below " +
                                  std::to_string(points.size()));
    query_of_input[queries[q]] = static_cast<uint32_t>(q);
  }
  PointMetrics out;
  out.query_index = queries;
  compute_queries(
      points, [&](uint32_t input) { return query_of_input[input]; }, options, out);
  return out;
}

Distribution summarize(const std::vector<float>& values, int histogram_bins) {
  Distribution d;
  std::vector<float> defined;
  defined.reserve(values.size());
  for (const float v : values) {
    if (std::isnan(v)) {
      ++d.undefined;
    } else {
      defined.push_back(v);
    }
  }
  d.count = defined.size();
  if (defined.empty()) return d;
  double sum = 0.0;
  float low = defined.front(), high = defined.front();
  for (const float v : defined) {
    sum += v;
    low = std::min(low, v);
    high = std::max(high, v);
  }
  d.mean = sum / static_cast<double>(d.count);
  double squares = 0.0;
  for (const float v : defined) squares += (v - d.mean) * (v - d.mean);
  d.std = std::sqrt(squares / static_cast<double>(d.count));  // population, like numpy
  d.min = low;
  d.max = high;
  const int bins = std::max(1, histogram_bins);
  const double width = (d.max - d.min) / bins;
  for (int b = 0; b <= bins; ++b) d.histogram_edges.push_back(d.min + b * width);
  d.histogram_counts.assign(static_cast<size_t>(bins), 0);
  for (const float v : defined) {
    const int bin = width > 0.0 ? static_cast<int>((v - d.min) / width) : 0;
    ++d.histogram_counts[static_cast<size_t>(std::clamp(bin, 0, bins - 1))];
  }
  // Selection, not a full sort (percentiles of millions of values).
  size_t selected = 0;
  d.p05 = quantile(&defined, 0.05, &selected);
  d.p25 = quantile(&defined, 0.25, &selected);
  d.median = quantile(&defined, 0.5, &selected);
  d.p75 = quantile(&defined, 0.75, &selected);
  d.p95 = quantile(&defined, 0.95, &selected);
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
