// Runs a stage's output tasks (files to encode and write, metrics to compute) on worker
// threads: the costliest first, as many side by side as a memory budget allows, with tasks
// added while others run. The map stage uses it so a sensor's outputs overlap the next
// sensors' scans and the last outputs keep every core busy without raising the memory peak.
// A task is a name, a cost estimate, a memory estimate and a function: nothing here knows what
// the tasks do.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace keel::pipeline {

// CPU seconds of the whole process / of the calling thread (POSIX CPU-time clocks).
double process_cpu_seconds();
double thread_cpu_seconds();
// Wall seconds from `start` to now (steady clock).
double seconds_since(std::chrono::steady_clock::time_point start);

// Runs tasks and keeps, per task, a line with its start (seconds after `origin`), wall and CPU
// seconds, for the job log. CPU is the task's own thread's: helper threads a task starts are
// not counted. `run` may be called from several threads at once.
class TaskLog {
 public:
  // Lines read "<label> <name> start ... s, ... s wall, ... s cpu".
  TaskLog(std::chrono::steady_clock::time_point origin, std::string label);
  // Runs `task`; an exception propagates and leaves no line.
  void run(const std::string& name, const std::function<void()>& task);
  // Passes the lines kept so far to `log`, in the order the tasks ended, and forgets them.
  void flush(const std::function<void(const std::string&)>& log);

 private:
  std::chrono::steady_clock::time_point origin_;
  std::string label_;
  std::mutex mutex_;
  std::vector<std::string> lines_;
};

// One task: `cost` (estimated CPU seconds, any consistent unit) orders the tasks costliest
// first; `bytes` (estimated peak allocation while it runs) bounds which may run side by side.
struct OutputTask {
  std::string name;
  double cost = 0.0;
  double bytes = 0.0;
  std::function<void()> run;
};

// Runs each task added exactly once, on worker threads. A free worker starts the costliest task
// not started whose bytes fit beside those of the running tasks within the memory budget (a
// task that would run alone always runs, whatever its bytes), so the cores stay busy to the
// end (the longest task first) without raising the memory peak. Tasks may be added while
// workers run, also by a task: workers leave only once no task runs that could still add one.
//
// After a task throws, no worker starts another task; finish() rethrows the first exception
// once the tasks running then have ended. Destroying the runner without finish() (an exception
// elsewhere) starts no further task and joins the workers, so everything the tasks use must
// outlive the runner (declare it after them).
class OutputRunner {
 public:
  explicit OutputRunner(TaskLog& log);
  ~OutputRunner();
  OutputRunner(const OutputRunner&) = delete;
  OutputRunner& operator=(const OutputRunner&) = delete;

  // Queues tasks; a running worker may start them at once. Safe from any thread, tasks too.
  void add(std::vector<OutputTask> tasks);
  // At least `threads` workers (>= 1) from now on, with this memory budget (bytes) for the
  // tasks started from now on. Until the first call no task starts. Not from a task.
  void run_with(int threads, double memory_budget);
  // No more tasks but those the running tasks add: waits for every task to run, calling
  // `done(fraction of the total cost done)` after each task that ends from now on (one call
  // at a time), and rethrows the first exception of a task. Not from a task.
  void finish(std::function<void(double)> done);
  // Rethrows the first task exception so far, if any, so a caller with other work (the map
  // stage between sensors) fails fast; tasks still running are joined by finish() or the
  // destructor.
  void rethrow_if_failed();

 private:
  size_t fitting() const;
  void work();

  TaskLog& log_;
  std::mutex mutex_;
  std::condition_variable changed_;  // tasks added, a task ended, budget set, closed, stopping
  std::deque<OutputTask> tasks_;     // a deque: references stay valid as tasks are added
  std::vector<bool> started_;
  size_t unstarted_ = 0, running_ = 0;
  double running_bytes_ = 0.0, memory_budget_ = 0.0, total_cost_ = 0.0, cost_done_ = 0.0;
  bool closed_ = false, stopping_ = false;
  std::exception_ptr error_;
  std::function<void(double)> done_;
  std::vector<std::thread> workers_;
};

}  // namespace keel::pipeline
