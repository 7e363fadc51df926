// Splits [0, n) into `threads` contiguous chunks run on std::threads (the calling thread takes
// the first); the first exception thrown by any chunk is rethrown after all have joined.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace keel::mapping {

template <typename Body>  // Body: void(size_t begin, size_t end)
void parallel_for(size_t n, int threads, const Body& body) {
  const size_t chunks = std::max<size_t>(1, std::min<size_t>(std::max(threads, 1), n));
  if (chunks <= 1 || n < 1024) {
    body(0, n);
    return;
  }
  std::exception_ptr error;
  std::mutex error_mutex;
  auto run = [&](size_t c) {
    try {
      body(n * c / chunks, n * (c + 1) / chunks);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
    }
  };
  std::vector<std::thread> workers;
  for (size_t c = 1; c < chunks; ++c) workers.emplace_back(run, c);
  run(0);
  for (std::thread& worker : workers) worker.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace keel::mapping
