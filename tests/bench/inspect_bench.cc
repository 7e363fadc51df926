// inspect: shape detection (Algorithm 1) + remeshing (Algorithm 2, Eq. 15) of seed 001 on a
// 100k-vertex flat-bottom hull patch with 20k features and 500 camera views; prints timings.
// Run build/tests/bench/bench_inspect.
#include <chrono>
#include <cstdio>
#include <random>

#include "tests/worker/inspect/synthetic_hull.h"
#include "worker/inspect/inspect.h"

namespace {

using keel::inspect::testing::Bump;
using keel::inspect::testing::SceneOptions;

SceneOptions bench_scene() {
  SceneOptions scene;
  scene.nx = scene.ny = 317;  // 100,489 vertices, 31.6 m x 31.6 m
  scene.spacing_m = 0.1;
  for (int i = 0; i < 25; ++i) {  // 25 x 20 = 500 views, lawnmower-like coverage at 1.5 m
    for (int j = 0; j < 20; ++j)
      scene.camera_xy.emplace_back(-14.0 + i * 28.0 / 24, -14.0 + j * 28.0 / 19);
  }
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> where(-13.0, 13.0), radius(0.2, 0.4), height(0.08, 0.2);
  for (int k = 0; k < 40; ++k) {  // 40 objects x 60 features
    scene.bumps.push_back(Bump{{where(rng), where(rng)}, radius(rng), height(rng), 60});
  }
  scene.num_hull_landmarks = 20000 - 40 * 60;
  return scene;
}

}  // namespace

int main() {
  const keel::inspect::InspectInput input = keel::inspect::testing::make_scene(bench_scene());
  size_t observations = 0;
  for (const auto& l : input.landmarks) observations += l.views.size();
  std::printf("scene: %zu vertices, %zu faces, %zu landmarks (%.1f views each), %zu views\n",
              input.cad_in_world.num_vertices(), input.cad_in_world.num_faces(),
              input.landmarks.size(), double(observations) / input.landmarks.size(),
              input.T_world_camera.size());
  const auto start = std::chrono::steady_clock::now();
  const keel::inspect::InspectResult result = keel::inspect::run_inspect(input);
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto& s = result.stats;
  std::printf("detections %d in %d views, %zu objects, %d Eq.(15) updates, %d vertices moved\n",
              s.num_detections, s.num_views_with_shapes, result.shapes.size(), s.num_updates,
              s.num_vertices_moved);
  std::printf("shape detection (Alg. 1) %.3f s, remeshing (Alg. 2) %.3f s, deviations %.3f s\n",
              s.detect_s, s.fuse_s, s.deviation_s);
  std::printf("detection + remeshing %.3f s; run_inspect total %.3f s\n", s.detect_s + s.fuse_s,
              total_s);
  return 0;
}
