#include "worker/stages/map/output_runner.h"

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <stdexcept>
#include <utility>

namespace keel::pipeline {

namespace {

double cpu_seconds(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double seconds_between(std::chrono::steady_clock::time_point from,
                       std::chrono::steady_clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

constexpr size_t kNone = static_cast<size_t>(-1);

}  // namespace

double process_cpu_seconds() { return cpu_seconds(CLOCK_PROCESS_CPUTIME_ID); }
double thread_cpu_seconds() { return cpu_seconds(CLOCK_THREAD_CPUTIME_ID); }
double seconds_since(std::chrono::steady_clock::time_point start) {
  return seconds_between(start, std::chrono::steady_clock::now());
}

// ---- TaskLog ------------------------------------------------------------------------------

TaskLog::TaskLog(std::chrono::steady_clock::time_point origin, std::string label)
    : origin_(origin), label_(std::move(label)) {}

void TaskLog::run(const std::string& name, const std::function<void()>& task) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = thread_cpu_seconds();
  task();
  char line[512];
  std::snprintf(line, sizeof(line), "%s %-28s start %6.2f s, %6.2f s wall, %6.2f s cpu",
                label_.c_str(), name.c_str(), seconds_between(origin_, start),
                seconds_between(start, std::chrono::steady_clock::now()),
                thread_cpu_seconds() - cpu_start);
  std::lock_guard<std::mutex> lock(mutex_);
  lines_.push_back(line);
}

void TaskLog::flush(const std::function<void(const std::string&)>& log) {
  std::vector<std::string> lines;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    lines.swap(lines_);
  }
  for (const auto& line : lines) log(line);
}

// ---- OutputRunner -------------------------------------------------------------------------

OutputRunner::OutputRunner(TaskLog& log) : log_(log) {}

OutputRunner::~OutputRunner() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  for (auto& worker : workers_) worker.join();
}

void OutputRunner::add(std::vector<OutputTask> tasks) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& task : tasks) {
      total_cost_ += task.cost;
      tasks_.push_back(std::move(task));
      started_.push_back(false);
      ++unstarted_;
    }
  }
  changed_.notify_all();
}

void OutputRunner::run_with(int threads, double memory_budget) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    memory_budget_ = memory_budget;
  }
  changed_.notify_all();
  while (workers_.size() < static_cast<size_t>(std::max(threads, 1)))
    workers_.emplace_back([this] { work(); });
}

void OutputRunner::finish(std::function<void(double)> done) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // Without workers nothing would run the tasks, and finish() would report success.
    if (workers_.empty() && unstarted_ > 0)
      throw std::logic_error("output runner: finish() with tasks left and no run_with()");
    done_ = std::move(done);
    closed_ = true;
  }
  changed_.notify_all();
  for (auto& worker : workers_) worker.join();
  workers_.clear();
  if (error_) std::rethrow_exception(error_);
}

void OutputRunner::rethrow_if_failed() {
  std::exception_ptr error;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    error = error_;
  }
  if (error) std::rethrow_exception(error);
}

// The costliest task not started that may start now, or kNone. Called with mutex_ held.
size_t OutputRunner::fitting() const {
  size_t best = kNone;
  for (size_t i = 0; i < tasks_.size(); ++i) {
    if (started_[i]) continue;
    if (running_ > 0 && running_bytes_ + tasks_[i].bytes > memory_budget_) continue;
    if (best == kNone || tasks_[i].cost > tasks_[best].cost) best = i;
  }
  return best;
}

void OutputRunner::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    size_t i = kNone;
    changed_.wait(lock, [&] {
      // A running task may still add tasks: no worker leaves before it ends.
      return error_ || stopping_ || (closed_ && unstarted_ == 0 && running_ == 0) ||
             (i = fitting()) != kNone;
    });
    if (error_ || stopping_ || i == kNone) return;
    started_[i] = true;
    --unstarted_;
    ++running_;
    running_bytes_ += tasks_[i].bytes;
    const std::string name = tasks_[i].name;
    const std::function<void()> run = tasks_[i].run;
    lock.unlock();
    std::exception_ptr failure;
    try {
      log_.run(name, run);
    } catch (...) {
      failure = std::current_exception();
    }
    lock.lock();
    --running_;
    running_bytes_ -= tasks_[i].bytes;
    if (failure && !error_) error_ = failure;
    cost_done_ += tasks_[i].cost;
    if (!failure && closed_ && done_ && total_cost_ > 0.0) done_(cost_done_ / total_cost_);
    changed_.notify_all();
  }
}

}  // namespace keel::pipeline
