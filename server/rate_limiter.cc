#include "server/rate_limiter.h"

#include <algorithm>

namespace keel::server {

std::optional<double> RateLimiter::take(const std::string& key, double now_s) {
  if (limit_.rate_per_s <= 0.0) return std::nullopt;
  std::lock_guard<std::mutex> lock(mutex_);
  auto found = buckets_.find(key);
  if (found == buckets_.end()) {
    if (buckets_.size() >= limit_.max_keys) forget_full_buckets(now_s);
    found = buckets_.emplace(key, Bucket{limit_.burst, now_s}).first;
  }
  Bucket& bucket = found->second;
  // Refill for the time since the last call (a clock going back refills nothing).
  const double elapsed = std::max(0.0, now_s - bucket.updated_s);
  bucket.tokens = std::min(limit_.burst, bucket.tokens + elapsed * limit_.rate_per_s);
  bucket.updated_s = std::max(bucket.updated_s, now_s);
  if (bucket.tokens >= 1.0 - 1e-9) {  // a whole token, whatever the rounding of the refill
    bucket.tokens -= 1.0;
    return std::nullopt;
  }
  return (1.0 - bucket.tokens) / limit_.rate_per_s;
}

void RateLimiter::forget_full_buckets(double now_s) {
  for (auto it = buckets_.begin(); it != buckets_.end();) {
    const double refilled = it->second.tokens + (now_s - it->second.updated_s) * limit_.rate_per_s;
    it = refilled >= limit_.burst ? buckets_.erase(it) : std::next(it);
  }
}

}  // namespace keel::server
