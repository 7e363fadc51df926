#include "server/request_counters.h"

namespace keel::server {

void RequestCounters::count(int status) {
  int digit = status / 100;
  if (digit < 1 || digit > 5) return;
  classes_[digit].fetch_add(1, std::memory_order_relaxed);
}

int64_t RequestCounters::by_class(int class_digit) const {
  if (class_digit < 1 || class_digit > 5) return 0;
  return classes_[class_digit].load(std::memory_order_relaxed);
}

}  // namespace keel::server
