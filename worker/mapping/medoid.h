// Exact medoid of a small point set: the member m minimising F(m) = sum_k |p_m - p_k|, the
// centre of Eq. (26), seed 000 ("v_bar = med(v_n) is the medoid").
//
// Brute force costs n^2 distances (2.6 M for the ~1600 neighbours of a 2 cm map at r = 0.25 m).
// Here F, extended to all of R^3, is convex, so after evaluating F and a subgradient g at a
// member y, F(x) >= F(y) + g.(x - y) for every x: each member in the half space
// g.(x - y) >= best - F(y) is no better than the best member so far and is dropped unevaluated.
// The next member evaluated is the survivor nearest the survivors' centroid, so each cut goes
// near the centre of what is left (a centre-of-gravity cutting-plane search over a finite
// set): about 2-3 log2(n) evaluations of O(n) each instead of n. The answer is exact; members
// whose sums differ by less than the float rounding of the sums (~1e-5 relative) are ties and
// either may be returned.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace keel::mapping {

struct MedoidScratch {
  std::vector<uint32_t> alive;
};

struct MedoidResult {
  size_t index = 0;         // into the n points
  double distance_sum = 0;  // F at the medoid
  int evaluations = 0;      // members whose F was computed (n for brute force)
};

// x, y, z: n coordinates each (n >= 1). Coordinates relative to a nearby origin keep the
// float sums accurate.
MedoidResult exact_medoid(const float* x, const float* y, const float* z, size_t n,
                          MedoidScratch* scratch);

}  // namespace keel::mapping
