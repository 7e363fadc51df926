// k-th smallest element by quickselect with a branchless Lomuto partition: the per-point
// medians of Eq. (26) run on ~50-500 values, where std::nth_element's branches mispredict about
// every other comparison (it was the largest cost of the map metrics, perf).
#pragma once

#include <cstddef>
#include <utility>

namespace keel::mapping {

// Reorders values[0, n) and returns the element of rank k (0-based, k < n), as
// std::nth_element would place at values[k].
template <typename T>
T select_kth(T* values, size_t n, size_t k) {
  size_t lo = 0, hi = n;  // the answer is in [lo, hi)
  while (hi - lo > 1) {
    // Median of three as the pivot value.
    T a = values[lo], b = values[lo + (hi - lo) / 2], c = values[hi - 1];
    if (b < a) std::swap(a, b);
    if (c < b) b = (c < a) ? a : c;
    const T pivot = b;
    // Branchless Lomuto: afterwards [lo, i) < pivot <= [i, hi).
    size_t i = lo;
    for (size_t j = lo; j < hi; ++j) {
      const T x = values[j];
      values[j] = values[i];
      values[i] = x;
      i += static_cast<size_t>(x < pivot);
    }
    if (k < i) {
      hi = i;
      continue;
    }
    // Same again with <=: [i, e) == pivot; non-empty because the pivot is in [i, hi).
    size_t e = i;
    for (size_t j = i; j < hi; ++j) {
      const T x = values[j];
      values[j] = values[e];
      values[e] = x;
      e += static_cast<size_t>(!(pivot < x));
    }
    if (k < e) return pivot;
    lo = e;
  }
  return values[lo];
}

}  // namespace keel::mapping
