// Splits [0, n) into `threads` contiguous chunks run on std::threads (the calling thread takes
// the first); the first exception thrown by any chunk is rethrown after all have joined.
// parallel_for_each below hands out single indices instead.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace keel {

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

// Calls body(i) for every i in [0, n) on up to `threads` threads, each thread taking the next i
// as soon as it is free: for a few tasks of very different costs, where parallel_for's equal
// chunks would leave a thread idle. The first exception stops the handing out of tasks and is
// rethrown after all have joined.
template <typename Body>  // Body: void(size_t i)
void parallel_for_each(size_t n, int threads, const Body& body) {
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto run = [&] {
    try {
      for (size_t i = next++; i < n; i = next++) body(i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = n;
    }
  };
  std::vector<std::thread> workers;
  const size_t count = std::min<size_t>(std::max(threads, 1), n);
  for (size_t t = 1; t < count; ++t) workers.emplace_back(run);
  run();
  for (std::thread& worker : workers) worker.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace keel
