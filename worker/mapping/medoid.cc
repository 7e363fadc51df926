#include "worker/mapping/medoid.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define KEEL_MEDOID_AVX2 1  // AVX2 kernels chosen at run time when the CPU has them
#endif

#include <algorithm>
#include <cmath>
#include <limits>

namespace keel::mapping {
namespace {

constexpr double kTieTolerance = 1e-5;  // relative: float rounding of the distance sums
constexpr float kInfinity = std::numeric_limits<float>::infinity();
// Factors that make rsqrtps / rcpps estimates (relative error <= 1.5 2^-12) one-sided.
constexpr float kEstimateUp = 1.0f + 1.0f / 1024, kEstimateDown = 1.0f - 1.0f / 1024;

// One O(n) pass at a point y (see medoid.h). Members equal to y contribute 0 to F, g and M
// and a unit ball's subgradient (zero is one).
struct Evaluation {
  double sum = 0.0;  // F(y)
  double g[3] = {0, 0, 0};
  double m[6] = {0, 0, 0, 0, 0, 0};  // M = sum u u^T: xx, yy, zz, xy, xz, yz
  double max_squared = 0.0;          // D^2
};

struct Point {
  float x, y, z;
};

void evaluate_scalar(const float* xs, const float* ys, const float* zs, size_t begin, size_t end,
                     Point p, Evaluation* e) {
  for (size_t k = begin; k < end; ++k) {
    const double dx = p.x - xs[k], dy = p.y - ys[k], dz = p.z - zs[k];
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 <= 0.0) continue;
    const double d = std::sqrt(d2), inverse = 1.0 / d;
    const double ux = dx * inverse, uy = dy * inverse, uz = dz * inverse;
    e->sum += d;
    e->g[0] += ux, e->g[1] += uy, e->g[2] += uz;
    e->m[0] += ux * ux, e->m[1] += uy * uy, e->m[2] += uz * uz;
    e->m[3] += ux * uy, e->m[4] += ux * uz, e->m[5] += uy * uz;
    e->max_squared = std::max(e->max_squared, d2);
  }
}

#if defined(__SSE2__)
double horizontal_sum(__m128 v) {
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, v);
  return (double(lanes[0]) + lanes[1]) + (double(lanes[2]) + lanes[3]);
}

// Four lanes of SSE2; 1/|d| from the hardware estimate refined by one Newton step (relative
// error ~1e-7, like a float division; the estimate alone, ~4e-4, would loosen the bounds'
// exactness) and |d| = |d|^2 / |d|: no sqrtps or divps, whose throughput bounds the loop.
void add_chunk_baseline(const float* xs, const float* ys, const float* zs, size_t n, Point p,
                        Evaluation* e) {
  const __m128 px = _mm_set1_ps(p.x), py = _mm_set1_ps(p.y), pz = _mm_set1_ps(p.z);
  const __m128 half = _mm_set1_ps(0.5f), three = _mm_set1_ps(3.0f), zero = _mm_setzero_ps();
  __m128d sum_low = _mm_setzero_pd(), sum_high = _mm_setzero_pd();  // F in double
  __m128 gx = zero, gy = zero, gz = zero, mxx = zero, myy = zero, mzz = zero, mxy = zero,
         mxz = zero, myz = zero, max_squared = zero;
  size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    const __m128 dx = _mm_sub_ps(px, _mm_loadu_ps(xs + k));
    const __m128 dy = _mm_sub_ps(py, _mm_loadu_ps(ys + k));
    const __m128 dz = _mm_sub_ps(pz, _mm_loadu_ps(zs + k));
    const __m128 d2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    const __m128 estimate = _mm_rsqrt_ps(d2);
    // Newton: e (3 - d2 e^2) / 2; lanes with d2 = 0 (inf estimate) are zeroed by the mask.
    __m128 inverse = _mm_mul_ps(_mm_mul_ps(half, estimate),
                                _mm_sub_ps(three, _mm_mul_ps(d2, _mm_mul_ps(estimate, estimate))));
    inverse = _mm_and_ps(inverse, _mm_cmpgt_ps(d2, zero));
    const __m128 d = _mm_mul_ps(d2, inverse);
    sum_low = _mm_add_pd(sum_low, _mm_cvtps_pd(d));
    sum_high = _mm_add_pd(sum_high, _mm_cvtps_pd(_mm_movehl_ps(d, d)));
    const __m128 ux = _mm_mul_ps(dx, inverse), uy = _mm_mul_ps(dy, inverse),
                 uz = _mm_mul_ps(dz, inverse);
    gx = _mm_add_ps(gx, ux);
    gy = _mm_add_ps(gy, uy);
    gz = _mm_add_ps(gz, uz);
    mxx = _mm_add_ps(mxx, _mm_mul_ps(ux, ux));
    myy = _mm_add_ps(myy, _mm_mul_ps(uy, uy));
    mzz = _mm_add_ps(mzz, _mm_mul_ps(uz, uz));
    mxy = _mm_add_ps(mxy, _mm_mul_ps(ux, uy));
    mxz = _mm_add_ps(mxz, _mm_mul_ps(ux, uz));
    myz = _mm_add_ps(myz, _mm_mul_ps(uy, uz));
    max_squared = _mm_max_ps(max_squared, d2);
  }
  const __m128d sum = _mm_add_pd(sum_low, sum_high);
  e->sum += _mm_cvtsd_f64(sum) + _mm_cvtsd_f64(_mm_unpackhi_pd(sum, sum));
  e->g[0] += horizontal_sum(gx), e->g[1] += horizontal_sum(gy), e->g[2] += horizontal_sum(gz);
  e->m[0] += horizontal_sum(mxx), e->m[1] += horizontal_sum(myy);
  e->m[2] += horizontal_sum(mzz), e->m[3] += horizontal_sum(mxy);
  e->m[4] += horizontal_sum(mxz), e->m[5] += horizontal_sum(myz);
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, max_squared);
  e->max_squared = std::max<double>(e->max_squared, *std::max_element(lanes, lanes + 4));
  evaluate_scalar(xs, ys, zs, k, n, p, e);
}
#else
void add_chunk_baseline(const float* xs, const float* ys, const float* zs, size_t n, Point p,
                        Evaluation* e) {
  evaluate_scalar(xs, ys, zs, 0, n, p, e);
}
#endif

// Float lanes sum at most kChunk members before their sums move to double: the rounding of g
// and M, on which the bounds rest, then grows like n (as the tie tolerance does), not n^2.
constexpr size_t kChunk = 512;

template <typename AddChunk>
Evaluation evaluate_in_chunks(const float* xs, const float* ys, const float* zs, size_t n, Point p,
                              AddChunk add_chunk) {
  Evaluation e;
  for (size_t begin = 0; begin < n; begin += kChunk) {
    add_chunk(xs + begin, ys + begin, zs + begin, std::min(kChunk, n - begin), p, &e);
  }
  return e;
}

Evaluation evaluate_baseline(const float* xs, const float* ys, const float* zs, size_t n, Point p) {
  return evaluate_in_chunks(xs, ys, zs, n, p, add_chunk_baseline);
}

// The bound of medoid.h and the Newton model of F about an evaluated point, in float.
struct Bound {
  Point at;
  float sum;         // F(at)
  float gx, gy, gz;  // g
  float a[6];        // n I - M: xx, yy, zz, 2 xy, 2 xz, 2 yz
  float twice_max;   // 2 D
  float curvature;   // model: F + g.delta + curvature * delta^T (n I - M) delta
  float threshold;   // members whose bound reaches this are ruled out
};

Bound make_bound(const Evaluation& e, Point at, size_t n, double best) {
  Bound b;
  b.at = at;
  b.sum = static_cast<float>(e.sum);
  b.gx = static_cast<float>(e.g[0]), b.gy = static_cast<float>(e.g[1]);
  b.gz = static_cast<float>(e.g[2]);
  const double count = static_cast<double>(n);
  b.a[0] = static_cast<float>(count - e.m[0]), b.a[1] = static_cast<float>(count - e.m[1]);
  b.a[2] = static_cast<float>(count - e.m[2]), b.a[3] = static_cast<float>(-2.0 * e.m[3]);
  b.a[4] = static_cast<float>(-2.0 * e.m[4]), b.a[5] = static_cast<float>(-2.0 * e.m[5]);
  b.twice_max = static_cast<float>(2.0 * std::sqrt(e.max_squared));
  // H = sum (I - u u^T) / d_k ~ (n I - M) / mean(d) = (n I - M) n / F: the model's Hessian (a
  // heuristic only; exactness rests on the bounds).
  b.curvature = static_cast<float>(e.sum > 0.0 ? 0.5 * count / e.sum : 0.0);
  b.threshold = std::isfinite(best) ? static_cast<float>(best * (1.0 + kTieTolerance)) : kInfinity;
  return b;
}

struct Pick {
  float model = kInfinity;
  size_t index = 0;
  bool found = false;
};

void tighten_scalar(const float* xs, const float* ys, const float* zs, size_t begin, size_t end,
                    const Bound& b, float* lower_bound, Pick* pick) {
  for (size_t k = begin; k < end; ++k) {
    const float dx = xs[k] - b.at.x, dy = ys[k] - b.at.y, dz = zs[k] - b.at.z;
    const float gd = b.gx * dx + b.gy * dy + b.gz * dz;
    const float q = b.a[0] * dx * dx + b.a[1] * dy * dy + b.a[2] * dz * dz + b.a[3] * dx * dy +
                    b.a[4] * dx * dz + b.a[5] * dy * dz;
    const float length = std::sqrt(dx * dx + dy * dy + dz * dz);
    const float denominator =
        std::max(b.twice_max + 2.0f * length, std::numeric_limits<float>::min());
    const float bound = std::max(lower_bound[k], b.sum + gd + q / denominator);
    lower_bound[k] = bound;
    const float model = std::max(bound, b.sum + gd + b.curvature * q);
    if (bound < b.threshold && (!pick->found || model < pick->model)) {
      *pick = {model, k, true};
    }
  }
}

// Raises every member's lower bound with b; returns the member not ruled out (bound below the
// threshold) that minimises the model, in pick (found = false when none is left).
#if defined(__SSE2__)
Pick tighten_baseline(const float* xs, const float* ys, const float* zs, size_t n, const Bound& b,
                      float* lower_bound) {
  const __m128 ax = _mm_set1_ps(b.at.x), ay = _mm_set1_ps(b.at.y), az = _mm_set1_ps(b.at.z);
  const __m128 gx = _mm_set1_ps(b.gx), gy = _mm_set1_ps(b.gy), gz = _mm_set1_ps(b.gz);
  const __m128 a0 = _mm_set1_ps(b.a[0]), a1 = _mm_set1_ps(b.a[1]), a2 = _mm_set1_ps(b.a[2]),
               a3 = _mm_set1_ps(b.a[3]), a4 = _mm_set1_ps(b.a[4]), a5 = _mm_set1_ps(b.a[5]);
  const __m128 twice_max = _mm_set1_ps(b.twice_max), sum = _mm_set1_ps(b.sum);
  const __m128 tiny = _mm_set1_ps(std::numeric_limits<float>::min());
  const __m128 up = _mm_set1_ps(kEstimateUp), down = _mm_set1_ps(kEstimateDown);
  const __m128 curvature = _mm_set1_ps(b.curvature), threshold = _mm_set1_ps(b.threshold);
  __m128 best_model = _mm_set1_ps(kInfinity);
  __m128i best_index = _mm_set1_epi32(-1);
  __m128i index = _mm_setr_epi32(0, 1, 2, 3);
  const __m128i four = _mm_set1_epi32(4);
  size_t k = 0;
  for (; k + 4 <= n; k += 4, index = _mm_add_epi32(index, four)) {
    const __m128 dx = _mm_sub_ps(_mm_loadu_ps(xs + k), ax);
    const __m128 dy = _mm_sub_ps(_mm_loadu_ps(ys + k), ay);
    const __m128 dz = _mm_sub_ps(_mm_loadu_ps(zs + k), az);
    const __m128 gd =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(gx, dx), _mm_mul_ps(gy, dy)), _mm_mul_ps(gz, dz));
    const __m128 xx = _mm_mul_ps(dx, dx), yy = _mm_mul_ps(dy, dy), zz = _mm_mul_ps(dz, dz);
    const __m128 q = _mm_add_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(a0, xx), _mm_mul_ps(a1, yy)), _mm_mul_ps(a2, zz)),
        _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(a3, _mm_mul_ps(dx, dy)), _mm_mul_ps(a4, _mm_mul_ps(dx, dz))),
            _mm_mul_ps(a5, _mm_mul_ps(dy, dz))));
    // |delta| overestimated and 1 / denominator underestimated by more than the hardware
    // estimates' error (1.5 2^-12): the bound only weakens, by 0.2 %, and no sqrtps or divps
    // (latency that bounded the loop) is needed. |delta| = 0 lanes (inf estimate) are zeroed.
    const __m128 d2 = _mm_add_ps(_mm_add_ps(xx, yy), zz);
    const __m128 length = _mm_and_ps(_mm_mul_ps(_mm_mul_ps(d2, _mm_rsqrt_ps(d2)), up),
                                     _mm_cmpgt_ps(d2, _mm_setzero_ps()));
    const __m128 denominator = _mm_max_ps(_mm_add_ps(twice_max, _mm_add_ps(length, length)), tiny);
    const __m128 quotient = _mm_mul_ps(_mm_mul_ps(q, _mm_rcp_ps(denominator)), down);
    // max(new, old): a member already evaluated holds +inf.
    const __m128 bound =
        _mm_max_ps(_mm_add_ps(_mm_add_ps(sum, gd), quotient), _mm_loadu_ps(lower_bound + k));
    _mm_storeu_ps(lower_bound + k, bound);
    const __m128 model =
        _mm_max_ps(bound, _mm_add_ps(_mm_add_ps(sum, gd), _mm_mul_ps(curvature, q)));
    const __m128 better =
        _mm_and_ps(_mm_cmplt_ps(bound, threshold), _mm_cmplt_ps(model, best_model));
    best_model = _mm_or_ps(_mm_and_ps(better, model), _mm_andnot_ps(better, best_model));
    const __m128i better_i = _mm_castps_si128(better);
    best_index =
        _mm_or_si128(_mm_and_si128(better_i, index), _mm_andnot_si128(better_i, best_index));
  }
  alignas(16) float models[4];
  alignas(16) int32_t indices[4];
  _mm_store_ps(models, best_model);
  _mm_store_si128(reinterpret_cast<__m128i*>(indices), best_index);
  Pick pick;
  for (int lane = 0; lane < 4; ++lane) {
    if (indices[lane] >= 0 && (!pick.found || models[lane] < pick.model)) {
      pick = {models[lane], static_cast<size_t>(indices[lane]), true};
    }
  }
  tighten_scalar(xs, ys, zs, k, n, b, lower_bound, &pick);
  return pick;
}
#else
Pick tighten_baseline(const float* xs, const float* ys, const float* zs, size_t n, const Bound& b,
                      float* lower_bound) {
  Pick pick;
  tighten_scalar(xs, ys, zs, 0, n, b, lower_bound, &pick);
  return pick;
}
#endif

#if defined(KEEL_MEDOID_AVX2)
// The kernels above on eight lanes, compiled for AVX2 only here and called only when the CPU
// reports it. Lanes past n hold copies of the evaluated point (d = 0: they add nothing) and are
// never picked or stored.
__attribute__((target("avx2"))) __m256i lanes_below(size_t remaining) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(std::min<size_t>(remaining, 8))),
                            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}

// Eight coordinates from p, or the lanes below `valid` only (maskload) in the last, partial
// step: a masked store or load costs far more than a plain one on some CPUs.
__attribute__((target("avx2"))) inline __m256 load8(const float* p, __m256i valid, bool full) {
  return full ? _mm256_loadu_ps(p) : _mm256_maskload_ps(p, valid);
}

__attribute__((target("avx2"))) double horizontal_sum_avx2(__m256 v) {
  alignas(32) float lanes[8];
  _mm256_store_ps(lanes, v);
  double sum = 0.0;
  for (const float lane : lanes) sum += lane;
  return sum;
}

__attribute__((target("avx2"))) void add_chunk_avx2(const float* xs, const float* ys,
                                                    const float* zs, size_t n, Point p,
                                                    Evaluation* e) {
  const __m256 px = _mm256_set1_ps(p.x), py = _mm256_set1_ps(p.y), pz = _mm256_set1_ps(p.z);
  const __m256 half = _mm256_set1_ps(0.5f), three = _mm256_set1_ps(3.0f);
  const __m256 zero = _mm256_setzero_ps();
  __m256d sum_low = _mm256_setzero_pd(), sum_high = _mm256_setzero_pd();  // F in double
  __m256 gx = zero, gy = zero, gz = zero, mxx = zero, myy = zero, mzz = zero, mxy = zero,
         mxz = zero, myz = zero, max_squared = zero;
  for (size_t k = 0; k < n; k += 8) {
    const bool full = k + 8 <= n;
    const __m256i valid = lanes_below(n - k);
    const __m256 mask = _mm256_castsi256_ps(valid);
    const __m256 dx = _mm256_sub_ps(px, _mm256_blendv_ps(px, load8(xs + k, valid, full), mask));
    const __m256 dy = _mm256_sub_ps(py, _mm256_blendv_ps(py, load8(ys + k, valid, full), mask));
    const __m256 dz = _mm256_sub_ps(pz, _mm256_blendv_ps(pz, load8(zs + k, valid, full), mask));
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                    _mm256_mul_ps(dz, dz));
    const __m256 estimate = _mm256_rsqrt_ps(d2);
    __m256 inverse =
        _mm256_mul_ps(_mm256_mul_ps(half, estimate),
                      _mm256_sub_ps(three, _mm256_mul_ps(d2, _mm256_mul_ps(estimate, estimate))));
    inverse = _mm256_and_ps(inverse, _mm256_cmp_ps(d2, zero, _CMP_GT_OQ));
    const __m256 d = _mm256_mul_ps(d2, inverse);
    sum_low = _mm256_add_pd(sum_low, _mm256_cvtps_pd(_mm256_castps256_ps128(d)));
    sum_high = _mm256_add_pd(sum_high, _mm256_cvtps_pd(_mm256_extractf128_ps(d, 1)));
    const __m256 ux = _mm256_mul_ps(dx, inverse), uy = _mm256_mul_ps(dy, inverse),
                 uz = _mm256_mul_ps(dz, inverse);
    gx = _mm256_add_ps(gx, ux);
    gy = _mm256_add_ps(gy, uy);
    gz = _mm256_add_ps(gz, uz);
    mxx = _mm256_add_ps(mxx, _mm256_mul_ps(ux, ux));
    myy = _mm256_add_ps(myy, _mm256_mul_ps(uy, uy));
    mzz = _mm256_add_ps(mzz, _mm256_mul_ps(uz, uz));
    mxy = _mm256_add_ps(mxy, _mm256_mul_ps(ux, uy));
    mxz = _mm256_add_ps(mxz, _mm256_mul_ps(ux, uz));
    myz = _mm256_add_ps(myz, _mm256_mul_ps(uy, uz));
    max_squared = _mm256_max_ps(max_squared, d2);
  }
  alignas(32) double sums[4];
  _mm256_store_pd(sums, _mm256_add_pd(sum_low, sum_high));
  e->sum += (sums[0] + sums[1]) + (sums[2] + sums[3]);
  e->g[0] += horizontal_sum_avx2(gx), e->g[1] += horizontal_sum_avx2(gy);
  e->g[2] += horizontal_sum_avx2(gz);
  e->m[0] += horizontal_sum_avx2(mxx), e->m[1] += horizontal_sum_avx2(myy);
  e->m[2] += horizontal_sum_avx2(mzz), e->m[3] += horizontal_sum_avx2(mxy);
  e->m[4] += horizontal_sum_avx2(mxz), e->m[5] += horizontal_sum_avx2(myz);
  alignas(32) float lanes[8];
  _mm256_store_ps(lanes, max_squared);
  e->max_squared = std::max<double>(e->max_squared, *std::max_element(lanes, lanes + 8));
}

Evaluation evaluate_avx2(const float* xs, const float* ys, const float* zs, size_t n, Point p) {
  return evaluate_in_chunks(xs, ys, zs, n, p, add_chunk_avx2);
}

__attribute__((target("avx2"))) Pick tighten_avx2(const float* xs, const float* ys, const float* zs,
                                                  size_t n, const Bound& b, float* lower_bound) {
  const __m256 ax = _mm256_set1_ps(b.at.x), ay = _mm256_set1_ps(b.at.y),
               az = _mm256_set1_ps(b.at.z);
  const __m256 gx = _mm256_set1_ps(b.gx), gy = _mm256_set1_ps(b.gy), gz = _mm256_set1_ps(b.gz);
  const __m256 a0 = _mm256_set1_ps(b.a[0]), a1 = _mm256_set1_ps(b.a[1]),
               a2 = _mm256_set1_ps(b.a[2]), a3 = _mm256_set1_ps(b.a[3]),
               a4 = _mm256_set1_ps(b.a[4]), a5 = _mm256_set1_ps(b.a[5]);
  const __m256 twice_max = _mm256_set1_ps(b.twice_max), sum = _mm256_set1_ps(b.sum);
  const __m256 tiny = _mm256_set1_ps(std::numeric_limits<float>::min());
  const __m256 up = _mm256_set1_ps(kEstimateUp), down = _mm256_set1_ps(kEstimateDown);
  const __m256 curvature = _mm256_set1_ps(b.curvature), threshold = _mm256_set1_ps(b.threshold);
  __m256 best_model = _mm256_set1_ps(kInfinity);
  __m256i best_index = _mm256_set1_epi32(-1);
  __m256i index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i eight = _mm256_set1_epi32(8);
  for (size_t k = 0; k < n; k += 8, index = _mm256_add_epi32(index, eight)) {
    const bool full = k + 8 <= n;
    const __m256i valid = lanes_below(n - k);
    const __m256 dx = _mm256_sub_ps(load8(xs + k, valid, full), ax);
    const __m256 dy = _mm256_sub_ps(load8(ys + k, valid, full), ay);
    const __m256 dz = _mm256_sub_ps(load8(zs + k, valid, full), az);
    const __m256 gd = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(gx, dx), _mm256_mul_ps(gy, dy)),
                                    _mm256_mul_ps(gz, dz));
    const __m256 xx = _mm256_mul_ps(dx, dx), yy = _mm256_mul_ps(dy, dy), zz = _mm256_mul_ps(dz, dz);
    const __m256 q =
        _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a0, xx), _mm256_mul_ps(a1, yy)),
                                    _mm256_mul_ps(a2, zz)),
                      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a3, _mm256_mul_ps(dx, dy)),
                                                  _mm256_mul_ps(a4, _mm256_mul_ps(dx, dz))),
                                    _mm256_mul_ps(a5, _mm256_mul_ps(dy, dz))));
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(xx, yy), zz);
    const __m256 length = _mm256_and_ps(_mm256_mul_ps(_mm256_mul_ps(d2, _mm256_rsqrt_ps(d2)), up),
                                        _mm256_cmp_ps(d2, _mm256_setzero_ps(), _CMP_GT_OQ));
    const __m256 denominator =
        _mm256_max_ps(_mm256_add_ps(twice_max, _mm256_add_ps(length, length)), tiny);
    const __m256 quotient = _mm256_mul_ps(_mm256_mul_ps(q, _mm256_rcp_ps(denominator)), down);
    const __m256 bound = _mm256_max_ps(_mm256_add_ps(_mm256_add_ps(sum, gd), quotient),
                                       _mm256_loadu_ps(lower_bound + k));
    _mm256_storeu_ps(lower_bound + k, bound);  // padded to whole vectors
    const __m256 model =
        _mm256_max_ps(bound, _mm256_add_ps(_mm256_add_ps(sum, gd), _mm256_mul_ps(curvature, q)));
    const __m256 better = _mm256_and_ps(
        _mm256_and_ps(_mm256_castsi256_ps(valid), _mm256_cmp_ps(bound, threshold, _CMP_LT_OQ)),
        _mm256_cmp_ps(model, best_model, _CMP_LT_OQ));
    best_model = _mm256_blendv_ps(best_model, model, better);
    best_index = _mm256_castps_si256(
        _mm256_blendv_ps(_mm256_castsi256_ps(best_index), _mm256_castsi256_ps(index), better));
  }
  alignas(32) float models[8];
  alignas(32) int32_t indices[8];
  _mm256_store_ps(models, best_model);
  _mm256_store_si256(reinterpret_cast<__m256i*>(indices), best_index);
  Pick pick;
  for (int lane = 0; lane < 8; ++lane) {
    if (indices[lane] >= 0 && (!pick.found || models[lane] < pick.model)) {
      pick = {models[lane], static_cast<size_t>(indices[lane]), true};
    }
  }
  return pick;
}

bool cpu_has_avx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}
#endif

// The widest kernels this CPU runs, unless told to use the baseline ones.
struct Kernels {
  bool avx2 = false;
  Evaluation evaluate(const float* xs, const float* ys, const float* zs, size_t n, Point p) const {
#if defined(KEEL_MEDOID_AVX2)
    if (avx2) return evaluate_avx2(xs, ys, zs, n, p);
#endif
    return evaluate_baseline(xs, ys, zs, n, p);
  }
  Pick tighten(const float* xs, const float* ys, const float* zs, size_t n, const Bound& b,
               float* lower_bound) const {
#if defined(KEEL_MEDOID_AVX2)
    if (avx2) return tighten_avx2(xs, ys, zs, n, b, lower_bound);
#endif
    return tighten_baseline(xs, ys, zs, n, b, lower_bound);
  }
};

Kernels kernels_for(const MedoidScratch& scratch) {
  Kernels kernels;
#if defined(KEEL_MEDOID_AVX2)
  kernels.avx2 = !scratch.baseline_kernels && cpu_has_avx2();
#endif
  return kernels;
}

// Only the first evaluation point: any point keeps the medoid exact, so float sums suffice.
Point centroid(const float* xs, const float* ys, const float* zs, size_t n) {
  double sx = 0, sy = 0, sz = 0;
  size_t k = 0;
#if defined(__SSE2__)
  __m128 vx = _mm_setzero_ps(), vy = _mm_setzero_ps(), vz = _mm_setzero_ps();
  for (; k + 4 <= n; k += 4) {
    vx = _mm_add_ps(vx, _mm_loadu_ps(xs + k));
    vy = _mm_add_ps(vy, _mm_loadu_ps(ys + k));
    vz = _mm_add_ps(vz, _mm_loadu_ps(zs + k));
  }
  sx = horizontal_sum(vx), sy = horizontal_sum(vy), sz = horizontal_sum(vz);
#endif
  for (; k < n; ++k) sx += xs[k], sy += ys[k], sz += zs[k];
  const double inverse = 1.0 / static_cast<double>(n);
  return {static_cast<float>(sx * inverse), static_cast<float>(sy * inverse),
          static_cast<float>(sz * inverse)};
}

}  // namespace

MedoidResult exact_medoid(const float* xs, const float* ys, const float* zs, size_t n,
                          MedoidScratch* scratch) {
  const Kernels kernels = kernels_for(*scratch);
  MedoidResult best;
  best.distance_sum = std::numeric_limits<double>::infinity();
  std::vector<float>& lower_bound = scratch->lower_bound;
  lower_bound.assign((n + 7) / 8 * 8, -kInfinity);  // whole vectors: lanes past n unused
  // The centroid, near the minimum of F over R^3, bounds every member and picks the first.
  Point at = centroid(xs, ys, zs, n);
  Evaluation e = kernels.evaluate(xs, ys, zs, n, at);
  best.evaluations = 1;
  while (true) {
    const Pick pick =
        kernels.tighten(xs, ys, zs, n, make_bound(e, at, n, best.distance_sum), lower_bound.data());
    if (!pick.found) break;  // every member not evaluated is proven no better
    const size_t m = pick.index;
    at = {xs[m], ys[m], zs[m]};
    e = kernels.evaluate(xs, ys, zs, n, at);
    ++best.evaluations;
    if (e.sum < best.distance_sum) {
      best.distance_sum = e.sum;
      best.index = m;
    }
    lower_bound[m] = kInfinity;  // F(m) is known: never picked again
  }
  return best;
}

}  // namespace keel::mapping
