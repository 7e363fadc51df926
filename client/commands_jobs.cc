// keel jobs [--state S] [--batch B [--follow]] | status <job> [--json] | cancel <job> |
// retry <job>
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>

#include "client/batch_progress.h"
#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "proto/job.h"

namespace keel::client {

namespace {

struct JobArgs {
  std::string job_id;
  std::string state;
  std::string batch;
  bool follow = false;
  double interval_s = 2.0;
  bool json = false;
};

// The batch's counts and ETA; with --follow, again every interval until nothing of it is
// queued or running. Exit code 4 when a job of the batch failed, 0 otherwise.
int run_batch(CliContext& context, const JobArgs& args) {
  for (;;) {
    const proto::Batch batch = context.api().get_batch(args.batch);
    std::fputs(format_batch_status(batch).c_str(), stdout);
    std::fflush(stdout);
    if (!args.follow || batch_finished(batch)) {
      auto failed = batch.jobs_by_state.find("failed");
      return failed != batch.jobs_by_state.end() && failed->second > 0 ? kExitJobFailed
                                                                       : kExitOk;
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(args.interval_s));
  }
}

int run_jobs(CliContext& context, const JobArgs& args) {
  if (!args.batch.empty()) return run_batch(context, args);
  if (!args.state.empty()) proto::job_state_from_string(args.state, "--state");
  const auto jobs = context.api().list_jobs(args.state);
  std::fputs(format_job_table(jobs).c_str(), stdout);
  return 0;
}

int run_status(CliContext& context, const JobArgs& args) {
  const proto::Job job = context.api().get_job(args.job_id);
  if (args.json) {
    std::printf("%s\n", job.to_json().dump(2).c_str());
  } else {
    std::fputs(format_job_status(job).c_str(), stdout);
  }
  return 0;
}

int run_cancel(CliContext& context, const JobArgs& args) {
  const proto::Job job = context.api().cancel_job(args.job_id);
  std::printf("%s %s\n", job.id.c_str(), proto::to_string(job.state).c_str());
  return 0;
}

int run_retry(CliContext& context, const JobArgs& args) {
  const proto::Job job = context.api().retry_job(args.job_id);
  std::printf("%s %s\n", job.id.c_str(), proto::to_string(job.state).c_str());
  return 0;
}

}  // namespace

void add_job_commands(CLI::App& app, CliContext& context) {
  auto args = std::make_shared<JobArgs>();

  CLI::App* jobs = app.add_subcommand("jobs", "List jobs, newest first");
  jobs->add_option("--state", args->state,
                   "Only jobs in this state (queued, running, succeeded, failed, canceled)");
  auto* batch = jobs->add_option("--batch", args->batch,
                                 "A reprocess batch: its jobs counted by state, and an ETA");
  jobs->add_flag("--follow", args->follow,
                 "With --batch: print again every --interval seconds until the batch is done")
      ->needs(batch);
  jobs->add_option("--interval", args->interval_s, "Seconds between two prints of --follow")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  jobs->callback([&context, args] { context.exit_code = run_jobs(context, *args); });

  CLI::App* status = app.add_subcommand("status", "Show one job");
  status->add_option("job", args->job_id, "Job id")->required();
  status->add_flag("--json", args->json, "Print the job as JSON");
  status->callback([&context, args] { context.exit_code = run_status(context, *args); });

  CLI::App* cancel = app.add_subcommand("cancel", "Cancel a queued or running job");
  cancel->add_option("job", args->job_id, "Job id")->required();
  cancel->callback([&context, args] { context.exit_code = run_cancel(context, *args); });

  CLI::App* retry = app.add_subcommand(
      "retry", "Queue a failed or canceled job again (finished stages are kept)");
  retry->add_option("job", args->job_id, "Job id")->required();
  retry->callback([&context, args] { context.exit_code = run_retry(context, *args); });
}

}  // namespace keel::client
