#include "worker/main/stop_signal.h"

#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <csignal>

namespace keel::worker {

namespace {

std::atomic<int> g_signal{0};
std::atomic<int64_t> g_first_signal_ns{0};
static_assert(std::atomic<int>::is_always_lock_free, "signal handlers need a lock-free flag");
static_assert(std::atomic<int64_t>::is_always_lock_free, "signal handlers need a lock-free clock");

// A repeat within this time is the same request delivered twice, not an impatient user:
// `scancel --signal=TERM --full` signals the worker and the batch shell, which forwards it.
constexpr int64_t kSameStopNs = 2'000'000'000;

int64_t monotonic_ns() {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);  // async-signal-safe
  return int64_t(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

extern "C" void on_stop_signal(int signal) {
  const int64_t now = monotonic_ns();
  int none = 0;
  if (g_signal.compare_exchange_strong(none, signal)) {
    g_first_signal_ns.store(now);
    return;
  }
  // A later signal means "now": the user has waited long enough for the current step.
  if (now - g_first_signal_ns.load() >= kSameStopNs) ::_exit(128 + signal);
}

}  // namespace

void install_stop_signals() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // loops poll stop_requested(); I/O calls just carry on
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool stop_requested() { return g_signal.load() != 0; }

int stop_signal() { return g_signal.load(); }

}  // namespace keel::worker
