// The token bucket against its closed form: after a burst of B, requests at a steady time
// are allowed at exactly rate R, and a refusal's wait is the time to the next whole token.
#include "server/rate_limiter.h"

#include <gtest/gtest.h>

namespace keel::server {
namespace {

TEST(RateLimiter, NoLimitAllowsEverything) {
  RateLimiter limiter({0.0, 1.0});
  for (int i = 0; i < 10000; ++i) EXPECT_FALSE(limiter.take("t", 0.0));
}

TEST(RateLimiter, ABurstThenTheRateWithTheExactWait) {
  RateLimiter limiter({10.0, 5.0});
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(limiter.take("t", 100.0)) << i;
  const auto wait = limiter.take("t", 100.0);
  ASSERT_TRUE(wait);
  EXPECT_NEAR(*wait, 0.1, 1e-12);  // one token at 10/s
  EXPECT_TRUE(limiter.take("t", 100.05));
  const auto half = limiter.take("t", 100.05);
  ASSERT_TRUE(half);
  EXPECT_NEAR(*half, 0.05, 1e-9);
  EXPECT_FALSE(limiter.take("t", 100.1));
  // Over 10 s of requests every millisecond, 10/s are allowed (plus the burst refilled
  // while it was spent: none here, the bucket is empty).
  int allowed = 0;
  for (int ms = 1; ms <= 10000; ++ms)
    if (!limiter.take("t", 100.1 + ms * 1e-3)) ++allowed;
  EXPECT_NEAR(allowed, 100, 1);
}

TEST(RateLimiter, KeysAreIndependentAndIdleKeysAreForgotten) {
  RateLimiter limiter({1.0, 2.0, /*max_keys=*/3});
  EXPECT_FALSE(limiter.take("a", 0.0));
  EXPECT_FALSE(limiter.take("a", 0.0));
  EXPECT_TRUE(limiter.take("a", 0.0));
  EXPECT_FALSE(limiter.take("b", 0.0));  // another token is not slowed by a
  EXPECT_FALSE(limiter.take("c", 0.0));
  // d makes the table full: b and c are not yet full again at t=0.5, a is not either.
  EXPECT_FALSE(limiter.take("d", 0.5));
  // Much later every bucket is full: a new key forgets them, and a starts afresh (2 at once).
  EXPECT_FALSE(limiter.take("e", 100.0));
  EXPECT_FALSE(limiter.take("a", 100.0));
  EXPECT_FALSE(limiter.take("a", 100.0));
  EXPECT_TRUE(limiter.take("a", 100.0));
}

TEST(RateLimiter, AClockGoingBackRefillsNothing) {
  RateLimiter limiter({1.0, 1.0});
  EXPECT_FALSE(limiter.take("t", 50.0));
  EXPECT_TRUE(limiter.take("t", 10.0));
  EXPECT_TRUE(limiter.take("t", 50.5));
  EXPECT_FALSE(limiter.take("t", 51.0));
}

}  // namespace
}  // namespace keel::server
