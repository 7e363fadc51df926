// MeshQuery throughput on a ~100k-triangle hull (a UV ellipsoid 60 x 12 x 8 m):
// raycasts/s (DVL beams and simulated range sensors) and signed-distance queries/s (the
// surface constraint, Eq. 4-5, seed 001), also for points that move a little between calls
// with and without LocalClosestPoint. Run build/tests/bench/bench_mesh_query.
#include <benchmark/benchmark.h>

#include <chrono>
#include <random>

#include "tests/core/mesh_fixtures.h"
#include "core/mesh_query.h"

namespace {

// 2 * 250 * 199 = 99,500 triangles.
const keel::TriangleMesh& hull() {
  static const keel::TriangleMesh mesh = keel::testing::make_uv_ellipsoid(250, 200, {30, 6, 4});
  return mesh;
}

const keel::MeshQuery& hull_query() {
  static const keel::MeshQuery query(hull());
  return query;
}

// Points within ~1 m of the hull surface, as features and survey positions are.
std::vector<Eigen::Vector3d> near_surface_points(size_t n, double sigma_m = 0.5) {
  std::mt19937 rng(1);
  std::uniform_int_distribution<size_t> vertex(0, hull().vertices.size() - 1);
  std::normal_distribution<double> noise(0, sigma_m);
  std::vector<Eigen::Vector3d> points;
  for (size_t i = 0; i < n; ++i) {
    points.push_back(hull().vertices[vertex(rng)] +
                     Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  return points;
}

// Beams from 2 m off the hull towards it, like a DVL on an inspection vehicle.
std::vector<keel::Ray> beams(size_t n) {
  std::mt19937 rng(2);
  std::uniform_int_distribution<size_t> vertex(0, hull().vertices.size() - 1);
  std::normal_distribution<double> noise(0, 0.3);
  std::vector<keel::Ray> rays;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d target = hull().vertices[vertex(rng)];
    const Eigen::Vector3d origin = target * (1.0 + 2.0 / target.norm());
    keel::Ray ray;
    ray.origin = origin;
    ray.direction = target - origin + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    ray.max_range_m = 30.0;
    rays.push_back(ray);
  }
  return rays;
}

void BM_Build(benchmark::State& state) {
  for (auto _ : state) {
    keel::MeshQuery query(hull());
    benchmark::DoNotOptimize(query.num_faces());
  }
  state.counters["triangles"] = static_cast<double>(hull().faces.size());
}

void BM_SignedDistance(benchmark::State& state) {
  const auto& query = hull_query();
  const auto points = near_surface_points(10000);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(query.signed_distance(points[i++ % points.size()]));
  }
  state.counters["distance_queries/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// The surface factor's access pattern (issue 6): landmarks within centimetres of the hull
// (sigma 2 cm), each queried once per Ceres evaluation after moving a little (state.range(0)
// micrometres per step, Gaussian per axis). The tree query per call, as the factor did...
void BM_SignedDistanceMoving(benchmark::State& state) {
  const auto& query = hull_query();
  auto points = near_surface_points(10000, 0.02);
  std::mt19937 rng(3);
  std::normal_distribution<double> step(0.0, 1e-6 * state.range(0));
  size_t i = 0;
  for (auto _ : state) {
    Eigen::Vector3d& p = points[i++ % points.size()];
    p += Eigen::Vector3d(step(rng), step(rng), step(rng));
    benchmark::DoNotOptimize(query.closest_point(p).signed_distance_m);
  }
  state.counters["distance_queries/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// ...and with one LocalClosestPoint per landmark, as the factor does now (anchored before the
// timing, as after the first Ceres evaluation; re-anchoring when a walk leaves rho is timed).
void BM_SignedDistanceMovingLocal(benchmark::State& state) {
  const auto& query = hull_query();
  auto points = near_surface_points(10000, 0.02);
  std::vector<keel::LocalClosestPoint> local(points.size(), keel::LocalClosestPoint(query));
  for (size_t k = 0; k < points.size(); ++k) local[k].closest_point(points[k]);
  std::mt19937 rng(3);
  std::normal_distribution<double> step(0.0, 1e-6 * state.range(0));
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ % points.size();
    points[k] += Eigen::Vector3d(step(rng), step(rng), step(rng));
    benchmark::DoNotOptimize(local[k].closest_point(points[k]).signed_distance_m);
  }
  int tree = 0, candidates = 0;
  for (const auto& l : local) {
    tree += l.tree_queries() - 1;
    candidates += static_cast<int>(l.num_candidates());
  }
  state.counters["distance_queries/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["tree_fraction"] = static_cast<double>(tree) / state.iterations();
  state.counters["mean_candidates"] = static_cast<double>(candidates) / local.size();
}

void BM_Raycast(benchmark::State& state) {
  const auto& query = hull_query();
  const auto rays = beams(10000);
  size_t i = 0, hits = 0;
  for (auto _ : state) {
    hits += query.raycast(rays[i++ % rays.size()]).has_value();
  }
  state.counters["raycasts/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["hit_fraction"] = static_cast<double>(hits) / state.iterations();
}

void BM_RaycastBatch2Threads(benchmark::State& state) {
  const auto& query = hull_query();
  const auto rays = beams(20000);
  for (auto _ : state) benchmark::DoNotOptimize(query.raycasts(rays, 2));
  state.counters["raycasts/s"] = benchmark::Counter(
      static_cast<double>(state.iterations() * rays.size()), benchmark::Counter::kIsRate);
}

BENCHMARK(BM_Build)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SignedDistance);
BENCHMARK(BM_SignedDistanceMoving)->Arg(1000)->Arg(10000);
BENCHMARK(BM_SignedDistanceMovingLocal)->Arg(1000)->Arg(10000);
BENCHMARK(BM_Raycast);
BENCHMARK(BM_RaycastBatch2Threads)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
