// keel watch <job> | log <job> [--from N] [--follow]
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>

#include "client/commands.h"
#include "client/job_watcher.h"

namespace keel::client {

namespace {

struct WatchArgs {
  std::string job_id;
  int64_t from = 0;
  bool follow = false;
  double interval_s = kDefaultPollInterval_s;
};

int run_watch(CliContext& context, const WatchArgs& args) {
  WatchOptions options;
  options.poll_interval_s = args.interval_s;
  return watch_job(context.api(), args.job_id, options);
}

int run_log(CliContext& context, const WatchArgs& args) {
  ApiClient& api = context.api();
  int64_t next = print_log(api, args.job_id, args.from);
  if (!args.follow) return 0;
  // Until the job ends, then once more for the lines written just before the end.
  while (!proto::is_terminal(api.get_job(args.job_id).state)) {
    std::this_thread::sleep_for(std::chrono::duration<double>(args.interval_s));
    next = print_log(api, args.job_id, next);
  }
  print_log(api, args.job_id, next);
  return 0;
}

}  // namespace

void add_watch_commands(CLI::App& app, CliContext& context) {
  auto args = std::make_shared<WatchArgs>();

  CLI::App* watch = app.add_subcommand(
      "watch",
      "Follow a job until it ends: stage, progress and new log lines (exit 4 failed, 5 canceled)");
  watch->add_option("job", args->job_id, "Job id")->required();
  watch->add_option("--interval", args->interval_s, "Seconds between polls")
      ->check(CLI::PositiveNumber);
  watch->callback([&context, args] { context.exit_code = run_watch(context, *args); });

  CLI::App* log = app.add_subcommand("log", "Print a job's log");
  log->add_option("job", args->job_id, "Job id")->required();
  log->add_option("--from", args->from, "First line number")->check(CLI::NonNegativeNumber);
  log->add_flag("-f,--follow", args->follow, "Keep printing new lines until the job ends");
  log->add_option("--interval", args->interval_s, "Seconds between polls with --follow")
      ->check(CLI::PositiveNumber);
  log->callback([&context, args] { context.exit_code = run_log(context, *args); });
}

}  // namespace keel::client
