// Runs produce(i) for i in [0, n) on `threads` threads and consume(i, result) in order of i
// (one call at a time), holding at most `max_waiting` results that wait for their turn; the
// thread that hands in the next result in order consumes it and every consecutive one ready,
// while the other threads go on producing. The first exception stops every thread and is
// rethrown. The map stage's tiles are filtered side by side but reach the output in tile order,
// so the output does not depend on timing.
#pragma once

#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace keel {

template <typename Result, typename Produce, typename Consume>
void ordered_parallel(size_t n, int threads, size_t max_waiting, const Produce& produce,
                      const Consume& consume) {
  std::mutex mutex;
  std::condition_variable changed;
  std::map<size_t, Result> ready;
  size_t next_task = 0, next_commit = 0;
  bool committing = false;
  std::exception_ptr error;
  const size_t waiting_limit = std::max<size_t>(1, max_waiting);

  auto worker = [&] {
    while (true) {
      size_t task = 0;
      {
        std::unique_lock<std::mutex> lock(mutex);
        changed.wait(lock, [&] { return error || ready.size() < waiting_limit; });
        if (error || next_task >= n) return;
        task = next_task++;
      }
      std::optional<Result> result;
      try {
        result.emplace(produce(task));
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
        changed.notify_all();
        return;
      }
      std::unique_lock<std::mutex> lock(mutex);
      if (error) return;
      ready.emplace(task, std::move(*result));
      if (committing) continue;
      committing = true;
      while (!error) {
        const auto it = ready.find(next_commit);
        if (it == ready.end()) break;
        Result item = std::move(it->second);
        ready.erase(it);
        changed.notify_all();
        lock.unlock();
        try {
          consume(next_commit, std::move(item));
        } catch (...) {
          lock.lock();
          if (!error) error = std::current_exception();
          break;
        }
        lock.lock();
        ++next_commit;
      }
      committing = false;
      changed.notify_all();
    }
  };
  std::vector<std::thread> pool;
  try {
    for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker);
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!error) error = std::current_exception();
  }
  worker();
  for (std::thread& thread : pool) thread.join();
  if (error) std::rethrow_exception(error);
  // Every task was produced and handed in; the last hand-in found no committer running, so
  // every result was consumed.
}

}  // namespace keel
