// keel missions [--prefix P] | reprocess (--mission ID... | --prefix P | --all)
//                                        [--stages a,b] [--set stage.option=value]... [--compare]
#include <cstdio>
#include <memory>

#include "client/cli_defaults.h"
#include "client/commands.h"
#include "client/job_format.h"
#include "proto/options.h"

namespace keel::client {

namespace {

struct MissionArgs {
  std::string prefix;
  std::vector<std::string> mission_ids;
  bool all = false;
  std::string stages = kDefaultStages;
  std::vector<std::string> assignments;
  bool compare = false;
};

int run_missions(CliContext& context, const MissionArgs& args) {
  std::fputs(format_mission_table(context.api().list_missions(args.prefix)).c_str(), stdout);
  return 0;
}

int run_reprocess(CliContext& context, const MissionArgs& args) {
  const int selectors = (!args.mission_ids.empty()) + (!args.prefix.empty()) + args.all;
  if (selectors != 1)
    throw CLI::ValidationError("reprocess", "give exactly one of --mission, --prefix or --all");
  proto::ReprocessRequest request;
  request.mission_ids = args.mission_ids;
  request.name_prefix = args.prefix;  // "" with --all: every mission
  request.stages = proto::parse_stage_list(args.stages);
  for (const auto& assignment : args.assignments)
    proto::apply_option_assignment(request.options, assignment);
  request.compare = args.compare;
  // The server makes every job in one transaction and answers at once, whatever the count.
  const auto reprocessed = context.api().reprocess(request);
  for (const proto::Job& job : reprocessed.jobs) std::printf("%s\n", job.id.c_str());
  std::fprintf(stderr, "batch %s: %ld jobs queued; follow it with: keel jobs --batch %s\n",
               reprocessed.batch.id.c_str(), long(reprocessed.batch.jobs),
               reprocessed.batch.id.c_str());
  if (args.compare)
    std::fprintf(stderr,
                 "%ld of them compare with the job they reprocess (the rest have no succeeded "
                 "job to compare with): their report's stages.compare, keel fetch for change_*\n",
                 long(reprocessed.batch.compared));
  return 0;
}

}  // namespace

void add_mission_commands(CLI::App& app, CliContext& context) {
  auto list_args = std::make_shared<MissionArgs>();
  CLI::App* missions = app.add_subcommand("missions", "List stored missions");
  missions->add_option("--prefix", list_args->prefix, "Only missions whose name starts with this");
  missions->callback(
      [&context, list_args] { context.exit_code = run_missions(context, *list_args); });

  auto args = std::make_shared<MissionArgs>();
  CLI::App* reprocess = app.add_subcommand(
      "reprocess", "Start new jobs on stored missions (nothing is uploaded again)");
  reprocess->add_option("--mission", args->mission_ids, "Mission id (repeatable)");
  reprocess->add_option("--prefix", args->prefix, "Missions whose name starts with this");
  reprocess->add_flag("--all", args->all, "Every stored mission");
  reprocess->add_option("--stages", args->stages, "Comma-separated stages to run")
      ->default_str(kDefaultStages);
  reprocess->add_option("--set", args->assignments,
                        "Stage option, stage.option=value (repeatable)");
  reprocess->add_flag("--compare", args->compare,
                      "Each new job then compares its products with the job it reprocesses "
                      "(its mission's latest succeeded job): stage compare, last");
  reprocess->callback([&context, args] { context.exit_code = run_reprocess(context, *args); });
}

}  // namespace keel::client
