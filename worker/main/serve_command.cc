// `keel-worker [serve] --server URL (--token T | --token-file F | env KEEL_TOKEN) ...`:
// lease jobs from a server and run them until SIGINT/SIGTERM.
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <memory>

#include "worker/main/commands.h"
#include "worker/main/lease_loop.h"
#include "worker/main/stop_signal.h"

namespace keel::worker {

namespace {

struct ServeArgs {
  std::string server;
  std::string token;
  std::string token_file;
  std::string cache_dir;
  std::string ca_file;
  LeaseLoopOptions loop;
  double request_timeout_s = 60.0;
  int parent_pid = 0;  // --exit-with-parent PID
};

// A worker started by keel-server must not outlive it: a SIGKILLed server would otherwise
// leave orphans leasing jobs from whatever listens on its old port next.
// The parent's pid comes from the parent itself: read here it could already be init's.
void stop_with_parent(pid_t parent) {
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (::getppid() != parent) ::raise(SIGTERM);  // the parent died before prctl took effect
}

std::filesystem::path default_cache_dir() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return std::filesystem::path(xdg) / "keel-worker";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::filesystem::path(home) / ".cache" / "keel-worker";
  return std::filesystem::temp_directory_path() / "keel-worker";
}

// --token, else --token-file (first line, trimmed), else $KEEL_TOKEN.
std::string resolve_token(const ServeArgs& args) {
  if (!args.token.empty()) return args.token;
  if (!args.token_file.empty()) {
    std::ifstream in(args.token_file);
    std::string line;
    if (!in || !std::getline(in, line))
      throw std::runtime_error("--token-file " + args.token_file + ": cannot read a token");
    const auto first = line.find_first_not_of(" \t\r\n");
    const auto last = line.find_last_not_of(" \t\r\n");
    if (first == std::string::npos)
      throw std::runtime_error("--token-file " + args.token_file + ": the first line is empty");
    return line.substr(first, last - first + 1);
  }
  if (const char* env = std::getenv("KEEL_TOKEN"); env && *env) return env;
  throw std::runtime_error("no token: give --token, --token-file or set KEEL_TOKEN");
}

int serve(const ServeArgs& args) {
  client::ClientConfig config;
  config.url = args.server;
  config.timeout_s = args.request_timeout_s;
  config.ca_file = args.ca_file;
  try {
    config.token = resolve_token(args);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kExitUsage;
  }
  LeaseLoopOptions options = args.loop;
  options.cache_dir =
      args.cache_dir.empty() ? default_cache_dir() : std::filesystem::path(args.cache_dir);
  install_stop_signals();
  if (args.parent_pid > 0) stop_with_parent(args.parent_pid);
  try {
    LeaseLoop loop(config, options);
    return loop.run(stop_requested);
  } catch (const std::exception& e) {
    // Only setup can fail here (cache folder not writable, bad URL): jobs never throw.
    spdlog::error("{}", e.what());
    return kExitUsage;
  }
}

}  // namespace

Subcommand add_serve_command(CLI::App& app) {
  auto args = std::make_shared<ServeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "serve", "Lease jobs from a Keel server and run them (the default subcommand)");
  cmd->add_option("--server", args->server, "Server URL, http://host:port or https://host:port")
      ->required();
  cmd->add_option("--ca-file", args->ca_file,
                  "https: PEM CA certificates to trust instead of the system's");
  auto* token = cmd->add_option("--token", args->token, "API token");
  cmd->add_option("--token-file", args->token_file, "File whose first line is the API token")
      ->excludes(token);
  cmd->add_option("--cache-dir", args->cache_dir,
                  "Blob cache and per-job work folders (default $XDG_CACHE_HOME/keel-worker)");
  cmd->add_option("--lease-seconds", args->loop.lease_seconds, "Lease time asked for")
      ->capture_default_str()
      ->check(CLI::Range(1, 3600));
  cmd->add_option("--wait-seconds", args->loop.wait_seconds,
                  "Long poll: how long the server may hold a lease call open (0 = poll)")
      ->capture_default_str()
      ->check(CLI::Range(0, 30));
  cmd->add_option("--poll-seconds", args->loop.poll_seconds,
                  "Pause when no job is queued (with --wait-seconds 0)")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 3600.0));
  cmd->add_option("--exit-when-idle", args->loop.exit_when_idle_s,
                  "Exit (0) after this many seconds without a job (Slurm arrays, autoscaling)")
      ->check(CLI::Range(0.0, 1e9));
  cmd->add_option("--heartbeat-seconds", args->loop.heartbeat_seconds, "Heartbeat period")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 60.0));
  cmd->add_option("--request-timeout", args->request_timeout_s, "Deadline of one HTTP request (s)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 3600.0));
  cmd->add_option("--name", args->loop.worker_name,
                  "Worker name (default host:pid:start-time, unique per process start)");
  cmd->add_flag("--once", args->loop.once, "Handle one job (waiting for it), then exit");
  cmd->add_flag("--keep-work", args->loop.keep_work, "Keep each job's work folder");
  cmd->add_option("--exit-with-parent", args->parent_pid,
                  "Stop (as on SIGTERM) when the parent process with this pid dies; keel-server "
                  "sets it")
      ->check(CLI::PositiveNumber);
  return {cmd, [args] { return serve(*args); }};
}

}  // namespace keel::worker
