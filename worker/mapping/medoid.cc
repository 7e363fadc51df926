#include "worker/mapping/medoid.h"

#include <Eigen/Core>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <limits>

namespace keel::mapping {
namespace {

struct Evaluation {
  double sum = 0.0;  // F(p)
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
};

// Members [begin, end) added to F and the subgradient at p in double.
void add_scalar_tail(const float* x, const float* y, const float* z, size_t begin, size_t end,
                     float px, float py, float pz, Evaluation* e) {
  for (size_t k = begin; k < end; ++k) {
    const double dx = px - x[k], dy = py - y[k], dz = pz - z[k];
    const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (d > 0.0) {
      e->sum += d;
      e->gradient += Eigen::Vector3d(dx, dy, dz) / d;
    }
  }
}

// F and a subgradient at p: sum_k (p - p_k) / |p - p_k| over p_k != p (a member equal to p
// contributes a subgradient from its unit ball; zero is one).
#if defined(__SSE2__)
// Four lanes of SSE; 1/|d| from the hardware estimate refined by one Newton step (relative error
// ~1e-7, like a float division; the estimate alone, ~4e-4, would blunt the cuts' exactness), and
// |d| = |d|^2 / |d|: no sqrtps or divps, whose throughput bounded the loop (perf).
Evaluation evaluate(const float* x, const float* y, const float* z, size_t n, float px, float py,
                    float pz) {
  const __m128 qx = _mm_set1_ps(px), qy = _mm_set1_ps(py), qz = _mm_set1_ps(pz);
  const __m128 half = _mm_set1_ps(0.5f), three = _mm_set1_ps(3.0f), zero = _mm_setzero_ps();
  __m128 sum = zero, gx = zero, gy = zero, gz = zero;
  size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    const __m128 dx = _mm_sub_ps(qx, _mm_loadu_ps(x + k));
    const __m128 dy = _mm_sub_ps(qy, _mm_loadu_ps(y + k));
    const __m128 dz = _mm_sub_ps(qz, _mm_loadu_ps(z + k));
    const __m128 d2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    const __m128 estimate = _mm_rsqrt_ps(d2);
    // Newton: e (3 - d2 e^2) / 2; lanes with d2 = 0 (inf estimate) are zeroed by the mask.
    __m128 inverse = _mm_mul_ps(_mm_mul_ps(half, estimate),
                                _mm_sub_ps(three, _mm_mul_ps(d2, _mm_mul_ps(estimate, estimate))));
    inverse = _mm_and_ps(inverse, _mm_cmpgt_ps(d2, zero));
    sum = _mm_add_ps(sum, _mm_mul_ps(d2, inverse));
    gx = _mm_add_ps(gx, _mm_mul_ps(dx, inverse));
    gy = _mm_add_ps(gy, _mm_mul_ps(dy, inverse));
    gz = _mm_add_ps(gz, _mm_mul_ps(dz, inverse));
  }
  alignas(16) float lanes[4][4];
  _mm_store_ps(lanes[0], sum);
  _mm_store_ps(lanes[1], gx);
  _mm_store_ps(lanes[2], gy);
  _mm_store_ps(lanes[3], gz);
  double totals[4] = {0, 0, 0, 0};
  for (int a = 0; a < 4; ++a) {
    for (int l = 0; l < 4; ++l) totals[a] += lanes[a][l];
  }
  Evaluation e;
  e.sum = totals[0];
  e.gradient = Eigen::Vector3d(totals[1], totals[2], totals[3]);
  add_scalar_tail(x, y, z, k, n, px, py, pz, &e);
  return e;
}
#else
Evaluation evaluate(const float* x, const float* y, const float* z, size_t n, float px, float py,
                    float pz) {
  Evaluation e;
  add_scalar_tail(x, y, z, 0, n, px, py, pz, &e);
  return e;
}
#endif

}  // namespace

MedoidResult exact_medoid(const float* xs, const float* ys, const float* zs, size_t n,
                          MedoidScratch* scratch) {
  MedoidResult best;
  best.distance_sum = std::numeric_limits<double>::infinity();
  std::vector<uint32_t>& alive = scratch->alive;  // survivors, compacted by each cut
  alive.resize(n);
  float sx = 0, sy = 0, sz = 0;  // survivors' coordinate sums (they only steer the next pick)
  for (size_t k = 0; k < n; ++k) {
    alive[k] = static_cast<uint32_t>(k);
    sx += xs[k];
    sy += ys[k];
    sz += zs[k];
  }
  while (!alive.empty()) {
    // The survivor nearest the survivors' centroid.
    const float inv = 1.0f / static_cast<float>(alive.size());
    const float mx = sx * inv, my = sy * inv, mz = sz * inv;
    size_t pick = 0;
    float nearest = std::numeric_limits<float>::infinity();
    for (size_t a = 0; a < alive.size(); ++a) {
      const uint32_t k = alive[a];
      const float d2 =
          (xs[k] - mx) * (xs[k] - mx) + (ys[k] - my) * (ys[k] - my) + (zs[k] - mz) * (zs[k] - mz);
      if (d2 < nearest) {
        nearest = d2;
        pick = a;
      }
    }
    const uint32_t m = alive[pick];
    const Evaluation e = evaluate(xs, ys, zs, n, xs[m], ys[m], zs[m]);
    ++best.evaluations;
    if (e.sum < best.distance_sum) {
      best.distance_sum = e.sum;
      best.index = m;
    }
    // Cut: drop x with F(m) + g.(x - m) >= best + tolerance (rounding of the float sums); the
    // evaluated member goes too.
    const double threshold = best.distance_sum * (1.0 + 1e-5) - e.sum;
    const float gx = static_cast<float>(e.gradient.x()), gy = static_cast<float>(e.gradient.y()),
                gz = static_cast<float>(e.gradient.z());
    const float offset = static_cast<float>(gx * xs[m] + gy * ys[m] + gz * zs[m] + threshold);
    size_t kept = 0;
    sx = sy = sz = 0;
    for (size_t a = 0; a < alive.size(); ++a) {
      const uint32_t k = alive[a];
      alive[kept] = k;
      if (a != pick && gx * xs[k] + gy * ys[k] + gz * zs[k] < offset) {
        sx += xs[k];
        sy += ys[k];
        sz += zs[k];
        ++kept;
      }
    }
    alive.resize(kept);
  }
  return best;
}

}  // namespace keel::mapping
