// Exact medoid of a small point set: the member m minimising F(m) = sum_k |p_m - p_k|, the
// centre of Eq. (26), seed 000 ("v_bar = med(v_n) is the medoid").
//
// Brute force costs n^2 distances. Here one O(n) pass at any point y gives F(y), the gradient
// g = sum_k u_k (u_k = (y - p_k) / |y - p_k|), M = sum_k u_k u_k^T and D = max_k |y - p_k|, and
// from them a lower bound on F at every member x = y + delta:
//   |p_k - x| = d_k + u_k.delta + (|delta|^2 - (u_k.delta)^2) / (|x - p_k| + d_k + u_k.delta)
//             >= d_k + u_k.delta + (|delta|^2 - (u_k.delta)^2) / (2 (D + |delta|)),
// summed: F(x) >= F(y) + g.delta + delta^T (n I - M) delta / (2 (D + |delta|)).
// Unlike the plane of convexity alone (F(y) + g.delta), the bound curves up like F itself, so
// after two or three evaluations near the minimum every other member is proven no better and
// is never evaluated (~2.7 O(n) passes on a 5 cm map's 56-point neighbourhoods, the centroid's
// included). Each member keeps the largest of its bounds; the next member evaluated is, among
// those not yet ruled out, the one minimising max(its bound, a Newton model of F about the last
// point evaluated): the model steers where F curves, the bounds where it is piecewise linear
// (collinear members). The first evaluation is at the centroid (not a member: it gives bounds
// but no candidate). The answer is exact; members whose sums differ by less than the float
// rounding of the sums (~1e-5 relative) are ties and either may be returned.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace keel::mapping {

struct MedoidScratch {
  std::vector<float> lower_bound;  // per member: the largest proven lower bound on F
  // The SSE2 kernels even where AVX2 ones run (both are tested; results agree to rounding).
  bool baseline_kernels = false;
};

struct MedoidResult {
  size_t index = 0;         // into the n points
  double distance_sum = 0;  // F at the medoid
  int evaluations = 0;      // O(n) evaluations of F (the centroid's included; n^2 brute force)
};

// x, y, z: n coordinates each (n >= 1). Coordinates relative to a nearby origin keep the
// float sums accurate.
MedoidResult exact_medoid(const float* x, const float* y, const float* z, size_t n,
                          MedoidScratch* scratch);

}  // namespace keel::mapping
