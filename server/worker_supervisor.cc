#include "server/worker_supervisor.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace keel::server {

namespace {

using Clock = std::chrono::steady_clock;

struct Slot {
  pid_t pid = 0;
  Clock::time_point started_at;
  Clock::time_point restart_at;
  std::chrono::milliseconds backoff{0};
};

std::string describe_exit(int status) {
  if (WIFEXITED(status)) return "exited with code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status))
    return std::string("was killed by signal ") + strsignal(WTERMSIG(status));
  return "stopped (status " + std::to_string(status) + ")";
}

}  // namespace

struct WorkerSupervisor::Impl {
  SupervisorOptions options;
  std::vector<std::string> worker_args;
  mutable std::mutex mutex;
  std::condition_variable wake;
  std::vector<Slot> slots;
  std::thread monitor;
  bool running = false;
  bool stopping = false;
  int restarts = 0;

  explicit Impl(SupervisorOptions o) : options(std::move(o)) {}

  std::filesystem::path log_path(size_t index) const {
    return options.log_dir / ("worker-" + std::to_string(index) + ".log");
  }

  // posix_spawn rather than fork: the server is multi-threaded.
  pid_t spawn(size_t index) {
    const std::string log = log_path(index).string();
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                     O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    // Nothing else of the server's: Asio opens its listening and connection sockets without
    // close-on-exec, and a worker that outlives a killed server (it stops at its next safe
    // point) would hold the listening port, so the restarted server could not bind it.
    posix_spawn_file_actions_addclosefrom_np(&actions, STDERR_FILENO + 1);

    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    sigset_t empty, defaults;
    sigemptyset(&empty);
    sigemptyset(&defaults);
    for (int signal_number : {SIGTERM, SIGINT, SIGHUP, SIGPIPE, SIGCHLD})
      sigaddset(&defaults, signal_number);
    posix_spawnattr_setsigmask(&attributes, &empty);  // the server blocks SIGTERM/SIGINT
    posix_spawnattr_setsigdefault(&attributes, &defaults);
    posix_spawnattr_setpgroup(&attributes, 0);
    posix_spawnattr_setflags(
        &attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETPGROUP);

    std::vector<std::string> args;
    args.push_back(options.worker_binary.string());
    args.insert(args.end(), worker_args.begin(), worker_args.end());
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);

    pid_t pid = 0;
    int error = posix_spawn(&pid, args[0].c_str(), &actions, &attributes, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    if (error != 0) {
      spdlog::error("worker {}: cannot start {}: {}", index, args[0], std::strerror(error));
      return 0;
    }
    spdlog::info("worker {}: started pid {} (log {})", index, pid, log);
    return pid;
  }

  // One pass: reap exited workers, schedule their restart, start the due ones. Holds mutex.
  void tick() {
    const auto now = Clock::now();
    for (size_t i = 0; i < slots.size(); ++i) {
      Slot& slot = slots[i];
      if (slot.pid > 0) {
        int status = 0;
        pid_t done = waitpid(slot.pid, &status, WNOHANG);
        if (done == 0) continue;
        const auto lived =
            std::chrono::duration_cast<std::chrono::milliseconds>(now - slot.started_at);
        if (lived >= options.stable_after) slot.backoff = std::chrono::milliseconds(0);
        slot.backoff = slot.backoff.count() == 0 ? options.initial_backoff
                                                 : std::min(options.max_backoff, slot.backoff * 2);
        ++restarts;
        spdlog::warn("worker {}: pid {} {} after {} ms; restarting in {} ms", i, slot.pid,
                     done < 0 ? "vanished" : describe_exit(status), lived.count(),
                     slot.backoff.count());
        slot.pid = 0;
        slot.restart_at = now + slot.backoff;
      }
      if (slot.pid == 0 && now >= slot.restart_at) {
        slot.pid = spawn(i);
        slot.started_at = now;
        if (slot.pid == 0) {  // could not even start: retry later with the same backoff rule
          slot.backoff = slot.backoff.count() == 0
                             ? options.initial_backoff
                             : std::min(options.max_backoff, slot.backoff * 2);
          slot.restart_at = now + slot.backoff;
        }
      }
    }
  }

  void monitor_loop() {
    std::unique_lock<std::mutex> lock(mutex);
    while (!stopping) {
      tick();
      wake.wait_for(lock, options.poll_interval, [this] { return stopping; });
    }
  }

  void terminate_all() {
    std::vector<pid_t> live;
    for (const Slot& slot : slots)
      if (slot.pid > 0) live.push_back(slot.pid);
    for (pid_t pid : live) kill(pid, SIGTERM);
    const auto deadline = Clock::now() + options.stop_grace;
    while (!live.empty()) {
      for (auto it = live.begin(); it != live.end();) {
        int status = 0;
        pid_t done = waitpid(*it, &status, WNOHANG);
        if (done != 0) {
          spdlog::info("worker pid {} {}", *it, done < 0 ? "is gone" : describe_exit(status));
          it = live.erase(it);
        } else {
          ++it;
        }
      }
      if (live.empty()) break;
      if (Clock::now() >= deadline) {
        for (pid_t pid : live) {
          spdlog::warn("worker pid {} ignored SIGTERM for {} ms; sending SIGKILL", pid,
                       options.stop_grace.count());
          kill(pid, SIGKILL);
          waitpid(pid, nullptr, 0);
        }
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    for (Slot& slot : slots) slot.pid = 0;
  }
};

WorkerSupervisor::WorkerSupervisor(SupervisorOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}

WorkerSupervisor::~WorkerSupervisor() { stop(); }

void WorkerSupervisor::start(std::vector<std::string> worker_args) {
  Impl& impl = *impl_;
  if (impl.options.workers <= 0) return;
  if (access(impl.options.worker_binary.c_str(), X_OK) != 0)
    throw std::runtime_error("worker binary " + impl.options.worker_binary.string() +
                             " is not an executable file (set --worker-binary)");
  std::error_code ec;
  std::filesystem::create_directories(impl.options.log_dir, ec);
  if (ec)
    throw std::runtime_error("cannot create " + impl.options.log_dir.string() + ": " +
                             ec.message());
  std::lock_guard<std::mutex> lock(impl.mutex);
  if (impl.running) return;
  impl.worker_args = std::move(worker_args);
  impl.slots.assign(static_cast<size_t>(impl.options.workers), Slot{});
  impl.tick();
  impl.running = true;
  impl.monitor = std::thread([&impl] { impl.monitor_loop(); });
}

void WorkerSupervisor::stop() {
  Impl& impl = *impl_;
  {
    std::lock_guard<std::mutex> lock(impl.mutex);
    if (!impl.running) return;
    impl.stopping = true;
  }
  impl.wake.notify_all();
  impl.monitor.join();
  std::lock_guard<std::mutex> lock(impl.mutex);
  impl.terminate_all();
  impl.running = false;
}

int WorkerSupervisor::alive() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return static_cast<int>(std::count_if(impl_->slots.begin(), impl_->slots.end(),
                                        [](const Slot& slot) { return slot.pid > 0; }));
}

std::vector<pid_t> WorkerSupervisor::pids() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  std::vector<pid_t> out;
  for (const Slot& slot : impl_->slots) out.push_back(slot.pid);
  return out;
}

int WorkerSupervisor::restarts() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->restarts;
}

}  // namespace keel::server
