// keel compare JOB_A JOB_B [--set compare.x=v]... [--wait]: a compare job over two finished
// jobs of one project, A the earlier (POST /v1/comparisons, issue 16). Prints the new job's id;
// --wait watches it to the end (exit codes as `keel watch`). A pair that cannot be compared is
// refused by the server with the reason (exit 2).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "client/commands.h"
#include "client/job_watcher.h"
#include "proto/job.h"
#include "proto/options.h"

namespace keel::client {
namespace {

struct CompareArgs {
  std::string job_a, job_b;
  std::vector<std::string> assignments;
  bool wait = false;
};

int run_compare(CliContext& context, const CompareArgs& args) {
  proto::ComparisonRequest request;
  request.job_a = args.job_a;
  request.job_b = args.job_b;
  nlohmann::json options = nlohmann::json::object();
  for (const auto& assignment : args.assignments) {
    if (assignment.rfind("compare.", 0) != 0)
      throw CLI::ValidationError("--set", "'" + assignment + "': only compare.<option>=<value>");
    proto::apply_option_assignment(options, assignment);
  }
  if (options.contains("compare")) request.options = options["compare"];
  const proto::Job job = proto::Job::from_json(
      context.api().post_json("/v1/comparisons", request.to_json()), "POST /v1/comparisons");
  std::printf("%s\n", job.id.c_str());
  std::fflush(stdout);
  if (!args.wait) return 0;
  return watch_job(context.api(), job.id, WatchOptions{});
}

}  // namespace

void add_compare_command(CLI::App& app, CliContext& context) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Compare two finished jobs (A earlier, B later): what changed between them");
  cmd->add_option("job-a", args->job_a, "The earlier job")->required();
  cmd->add_option("job-b", args->job_b, "The later job")->required();
  cmd->add_option("--set", args->assignments, "compare.option=value (repeatable)");
  cmd->add_flag("--wait", args->wait, "Watch the job until it ends; exit code tells how it ended");
  cmd->callback([&context, args] { context.exit_code = run_compare(context, *args); });
}

}  // namespace keel::client
