#include "worker/main/stop_signal.h"

#include <unistd.h>

#include <atomic>
#include <csignal>

namespace keel::worker {

namespace {

std::atomic<int> g_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "signal handlers need a lock-free flag");

extern "C" void on_stop_signal(int signal) {
  // A second signal means "now": the user has waited long enough for the current step.
  if (g_signal.exchange(signal) != 0) ::_exit(128 + signal);
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
