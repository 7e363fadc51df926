// Per-key request rate limit (a token bucket per API token): each key may make `burst`
// requests at once and `rate_per_s` per second on average. A refused request learns how long
// until it may try again (the 429's Retry-After). Thread-safe; the time is passed in, so the
// limiter is a pure function of its calls. Keys idle long enough to have a full bucket are
// forgotten when the table grows past `max_keys`, so a flood of distinct tokens (all of
// which were authenticated first) cannot grow it without bound.
#pragma once

#include <cstddef>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

namespace keel::server {

struct RateLimit {
  double rate_per_s = 0.0;  // 0 = no limit
  double burst = 1.0;       // requests allowed at once (the bucket's size), >= 1
  size_t max_keys = 100'000;
};

class RateLimiter {
 public:
  explicit RateLimiter(RateLimit limit) : limit_(limit) {}

  // nullopt: allowed (one request taken). Else the seconds until one request is allowed.
  std::optional<double> take(const std::string& key, double now_s);

 private:
  struct Bucket {
    double tokens = 0.0;
    double updated_s = 0.0;
  };
  void forget_full_buckets(double now_s);

  RateLimit limit_;
  std::mutex mutex_;
  std::unordered_map<std::string, Bucket> buckets_;
};

}  // namespace keel::server
