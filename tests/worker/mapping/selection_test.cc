// select_kth against std::sort on random, duplicate-heavy and sorted inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "worker/mapping/selection.h"

namespace keel::mapping {
namespace {

TEST(SelectKth, MatchesSortingForEveryRank) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 300; ++trial) {
    const size_t n = 1 + rng() % 200;
    const int distinct = trial % 3 == 0 ? 3 : 1000;  // many duplicates in a third of the trials
    std::vector<float> values(n);
    for (float& v : values) v = static_cast<float>(static_cast<int>(rng() % distinct)) * 0.5f;
    if (trial % 7 == 0) std::sort(values.begin(), values.end());
    if (trial % 11 == 0) std::sort(values.rbegin(), values.rend());
    std::vector<float> sorted = values;
    std::sort(sorted.begin(), sorted.end());
    for (size_t k = 0; k < n; k += 1 + n / 17) {
      std::vector<float> work = values;
      ASSERT_EQ(select_kth(work.data(), n, k), sorted[k]) << "n " << n << " k " << k;
      std::sort(work.begin(), work.end());
      ASSERT_EQ(work, sorted);  // a permutation of the input
    }
  }
}

}  // namespace
}  // namespace keel::mapping
