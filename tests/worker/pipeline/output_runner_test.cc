#include "worker/stages/map/output_runner.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace keel::pipeline {
namespace {

// What the tasks did, in the order they did it: "start <name>" / "end <name>" events appended
// under a mutex from inside the task functions.
class EventLog {
 public:
  void record(const std::string& event, const std::string& name) {
    std::lock_guard<std::mutex> lock(mutex_);
    events_.push_back({event, name});
  }
  std::vector<std::pair<std::string, std::string>> events() {
    std::lock_guard<std::mutex> lock(mutex_);
    return events_;
  }
  std::vector<std::string> starts() {
    std::vector<std::string> names;
    for (const auto& [event, name] : events())
      if (event == "start") names.push_back(name);
    return names;
  }

 private:
  std::mutex mutex_;
  std::vector<std::pair<std::string, std::string>> events_;
};

// A task that records its start and end, and gives other workers a chance to overlap it (the
// sleep makes overlaps likely; nothing asserts how long anything takes).
OutputTask recorded(EventLog& log, const std::string& name, double cost, double bytes,
                    std::chrono::milliseconds busy = std::chrono::milliseconds(0)) {
  return {name, cost, bytes, [&log, name, busy] {
            log.record("start", name);
            if (busy.count() > 0) std::this_thread::sleep_for(busy);
            log.record("end", name);
          }};
}

std::chrono::steady_clock::time_point now() { return std::chrono::steady_clock::now(); }

TEST(OutputRunner, RunsEveryTaskExactlyOnce) {
  TaskLog task_log(now(), "test");
  EventLog events;
  {
    OutputRunner runner(task_log);
    std::vector<OutputTask> tasks;
    for (int i = 0; i < 40; ++i)
      tasks.push_back(recorded(events, "t" + std::to_string(i), i % 7, 1.0));
    runner.add(std::move(tasks));
    runner.run_with(4, 1e9);
    runner.finish([](double) {});
  }
  std::map<std::string, int> starts, ends;
  for (const auto& [event, name] : events.events()) ++(event == "start" ? starts : ends)[name];
  ASSERT_EQ(starts.size(), 40u);
  ASSERT_EQ(ends.size(), 40u);
  for (const auto& [name, count] : starts) EXPECT_EQ(count, 1) << name;
  for (const auto& [name, count] : ends) EXPECT_EQ(count, 1) << name;
}

TEST(OutputRunner, OneThreadStartsCostliestFirst) {
  TaskLog task_log(now(), "test");
  EventLog events;
  OutputRunner runner(task_log);
  const std::vector<double> costs = {3.0, 9.0, 0.5, 7.0, 1.0, 8.0, 2.0};
  std::vector<OutputTask> tasks;
  for (double cost : costs) tasks.push_back(recorded(events, std::to_string(cost), cost, 1.0));
  runner.add(std::move(tasks));
  runner.run_with(1, 0.0);
  runner.finish([](double) {});
  std::vector<double> sorted = costs;
  std::sort(sorted.begin(), sorted.end(), std::greater<double>());
  std::vector<std::string> expected;
  for (double cost : sorted) expected.push_back(std::to_string(cost));
  EXPECT_EQ(events.starts(), expected);
}

// Replays the events: whenever two or more tasks run at once, their bytes must fit the budget.
// The events are recorded inside the tasks, so the tasks seen running are among those the
// runner counts as running, and the bound holds for them too.
void expect_within_budget(const std::vector<std::pair<std::string, std::string>>& events,
                          const std::map<std::string, double>& bytes, double budget,
                          int* max_running = nullptr) {
  std::set<std::string> running;
  for (const auto& [event, name] : events) {
    if (event == "end") {
      running.erase(name);
      continue;
    }
    running.insert(name);
    if (max_running) *max_running = std::max(*max_running, static_cast<int>(running.size()));
    if (running.size() < 2) continue;
    double total = 0.0;
    std::string names;
    for (const auto& r : running) {
      total += bytes.at(r);
      names += r + " ";
    }
    EXPECT_LE(total, budget) << "running together: " << names;
  }
}

TEST(OutputRunner, TasksOverBudgetTogetherNeverOverlap) {
  TaskLog task_log(now(), "test");
  EventLog events;
  std::map<std::string, double> bytes;
  const double budget = 10.0;
  {
    OutputRunner runner(task_log);
    std::vector<OutputTask> tasks;
    // Big tasks (6 bytes: two exceed the budget), small ones (3: three fit, or one beside a
    // big one), and one over the budget on its own, which must still run, alone.
    const std::vector<std::pair<double, int>> kinds = {{6.0, 6}, {3.0, 10}, {12.0, 1}};
    int k = 0;
    for (const auto& [b, count] : kinds)
      for (int i = 0; i < count; ++i, ++k) {
        const std::string name =
            "b" + std::to_string(static_cast<int>(b)) + "_" + std::to_string(i);
        bytes[name] = b;
        tasks.push_back(recorded(events, name, (k * 7) % 5, b, std::chrono::milliseconds(5)));
      }
    runner.add(std::move(tasks));
    runner.run_with(4, budget);
    runner.finish([](double) {});
  }
  EXPECT_EQ(events.starts().size(), bytes.size());
  expect_within_budget(events.events(), bytes, budget);
}

TEST(OutputRunner, TasksThatFitRunSideBySide) {
  // Two tasks that each wait for the other to have started: they finish only if the runner
  // runs them at once (the wait is bounded so a failure does not hang the test).
  TaskLog task_log(now(), "test");
  std::mutex mutex;
  std::condition_variable cv;
  int started = 0;
  bool both_seen[2] = {false, false};
  auto meet = [&](int who) {
    std::unique_lock<std::mutex> lock(mutex);
    ++started;
    cv.notify_all();
    both_seen[who] = cv.wait_for(lock, std::chrono::seconds(30), [&] { return started == 2; });
  };
  OutputRunner runner(task_log);
  runner.add({{"a", 1.0, 4.0, [&] { meet(0); }}, {"b", 1.0, 4.0, [&] { meet(1); }}});
  runner.run_with(2, 8.0);
  runner.finish([](double) {});
  EXPECT_TRUE(both_seen[0]);
  EXPECT_TRUE(both_seen[1]);
}

TEST(OutputRunner, ExceptionIsRethrownAndNoTaskStartsAfterIt) {
  TaskLog task_log(now(), "test");
  EventLog events;
  OutputRunner runner(task_log);
  runner.add({recorded(events, "first", 3.0, 1.0),
              {"fails", 2.0, 1.0,
               [&] {
                 events.record("start", "fails");
                 throw std::runtime_error("disk full");
               }},
              recorded(events, "after", 1.0, 1.0)});
  runner.run_with(1, 0.0);
  try {
    runner.finish([](double) {});
    FAIL() << "finish() did not rethrow";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "disk full");
  }
  EXPECT_EQ(events.starts(), (std::vector<std::string>{"first", "fails"}));
}

TEST(OutputRunner, TasksAddedWhileRunningStillRun) {
  TaskLog task_log(now(), "test");
  EventLog events;
  std::vector<double> fractions;
  {
    OutputRunner runner(task_log);
    // Workers first, as the map stage starts a sensor's outputs while others still scan.
    runner.run_with(1, 0.0);
    runner.add({recorded(events, "early", 1.0, 0.0)});
    runner.add({recorded(events, "early 2", 1.0, 0.0)});
    // A task that adds its follow-up (the combined Draco encode adds its check).
    runner.add({{"parent", 5.0, 1.0,
                 [&] {
                   events.record("start", "parent");
                   std::this_thread::sleep_for(std::chrono::milliseconds(20));
                   runner.add({recorded(events, "child", 2.0, 1.0)});
                   events.record("end", "parent");
                 }},
                recorded(events, "late", 1.0, 0.0)});
    runner.run_with(2, 1.0);
    runner.finish([&](double f) { fractions.push_back(f); });
  }
  std::vector<std::string> starts = events.starts();
  std::sort(starts.begin(), starts.end());
  EXPECT_EQ(starts, (std::vector<std::string>{"child", "early", "early 2", "late", "parent"}));
  // The child starts after its parent did.
  const auto all = events.events();
  const auto at = [&](const std::string& event, const std::string& name) {
    return std::find(all.begin(), all.end(), std::make_pair(event, name)) - all.begin();
  };
  EXPECT_LT(at("start", "parent"), at("start", "child"));
  // Progress is reported for the tasks that end after finish() is called (here almost surely
  // some: the parent sleeps); the last of them completes the whole cost, the child's included.
  for (double f : fractions) {
    EXPECT_GT(f, 0.0);
    EXPECT_LE(f, 1.0);
  }
  if (!fractions.empty()) {
    EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  }
}

TEST(OutputRunner, DestroyedWithoutFinishStartsNothingMore) {
  // No workers were asked for: destroying the runner (as on an exception before finish())
  // must neither run the queued tasks nor hang.
  TaskLog task_log(now(), "test");
  EventLog events;
  {
    OutputRunner runner(task_log);
    runner.add({recorded(events, "never", 1.0, 0.0)});
  }
  EXPECT_TRUE(events.events().empty());
}

TEST(OutputRunner, AFailedTaskIsReportedBeforeFinish) {
  TaskLog task_log(now(), "test");
  OutputRunner runner(task_log);
  EXPECT_NO_THROW(runner.rethrow_if_failed());
  std::atomic<bool> thrown{false};
  runner.add({{"fails", 1.0, 1.0, [&] {
                 thrown = true;
                 throw std::runtime_error("disk full");
               }}});
  runner.run_with(1, 1e9);
  while (!thrown) std::this_thread::yield();
  // The error is recorded after the throw leaves the task; poll until it is (the deadline
  // only keeps a broken runner from hanging the test).
  bool reported = false;
  const auto deadline = now() + std::chrono::seconds(30);
  while (!reported && now() < deadline) {
    try {
      runner.rethrow_if_failed();
      std::this_thread::yield();
    } catch (const std::runtime_error& e) {
      reported = std::string(e.what()) == "disk full";
    }
  }
  EXPECT_TRUE(reported);
  EXPECT_THROW(runner.finish([](double) {}), std::runtime_error);
}

TEST(OutputRunner, FinishWithoutWorkersRefusesToReportSuccess) {
  TaskLog task_log(now(), "test");
  EventLog events;
  OutputRunner runner(task_log);
  runner.add({recorded(events, "never", 1.0, 1.0)});
  EXPECT_THROW(runner.finish([](double) {}), std::logic_error);
  EXPECT_TRUE(events.starts().empty());
}

TEST(TaskLog, KeepsOneLinePerTaskThatEnded) {
  TaskLog task_log(now(), "label:");
  task_log.run("alpha", [] {});
  EXPECT_THROW(task_log.run("broken", [] { throw std::runtime_error("x"); }), std::runtime_error);
  task_log.run("beta", [] {});
  std::vector<std::string> lines;
  task_log.flush([&](const std::string& line) { lines.push_back(line); });
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].rfind("label: alpha", 0), 0u) << lines[0];
  EXPECT_EQ(lines[1].rfind("label: beta", 0), 0u) << lines[1];
  EXPECT_NE(lines[0].find(" s cpu"), std::string::npos) << lines[0];
  lines.clear();
  task_log.flush([&](const std::string& line) { lines.push_back(line); });
  EXPECT_TRUE(lines.empty());
}

TEST(CpuSeconds, ThreadClockAdvancesWithWork) {
  const double start = thread_cpu_seconds();
  volatile double sink = 0.0;
  for (int i = 0; thread_cpu_seconds() <= start && i < 100000000; ++i) sink = sink + i;
  EXPECT_GT(thread_cpu_seconds(), start);
  EXPECT_GE(process_cpu_seconds(), thread_cpu_seconds() - 1e-3);
}

}  // namespace
}  // namespace keel::pipeline
