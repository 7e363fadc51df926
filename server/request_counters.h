// Answered requests by status class, for /metrics. Lock-free: every io thread counts.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <string>

namespace keel::server {

class RequestCounters {
 public:
  void count(int status);
  // Answers so far in class "1xx".."5xx" (index 1..5).
  int64_t by_class(int class_digit) const;

 private:
  std::array<std::atomic<int64_t>, 6> classes_{};
};

}  // namespace keel::server
