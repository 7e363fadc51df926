// keel submit <mission-dir> [--cad mesh] [--stages a,b] [--set stage.option=value]...
//             [--name N] [--cache-dir D] [--wait]
#include <cstdio>
#include <memory>

#include "client/cli_defaults.h"
#include "client/commands.h"
#include "client/job_watcher.h"
#include "client/submit.h"
#include "proto/options.h"

namespace keel::client {

namespace {

struct SubmitArgs {
  std::string mission_dir;
  std::string cad;
  std::string stages = kDefaultStages;
  std::vector<std::string> assignments;
  std::string name;
  std::string cache_dir;
  bool wait = false;
  bool quiet = false;
};

int run_submit(CliContext& context, const SubmitArgs& args) {
  SubmitOptions options;
  options.mission_dir = args.mission_dir;
  options.cad_file = args.cad;
  options.stages = proto::parse_stage_list(args.stages);
  for (const auto& assignment : args.assignments)
    proto::apply_option_assignment(options.options, assignment);
  options.name = args.name;
  options.cache_dir = args.cache_dir.empty() ? default_cache_dir() : args.cache_dir;
  options.show_progress = !args.quiet;
  const SubmitResult result = submit_mission(context.api(), options);
  std::printf("%s\n", result.job.id.c_str());
  std::fflush(stdout);
  if (!args.wait) return 0;
  WatchOptions watch;
  watch.show_progress = !args.quiet;
  return watch_job(context.api(), result.job.id, watch);
}

}  // namespace

void add_submit_command(CLI::App& app, CliContext& context) {
  auto args = std::make_shared<SubmitArgs>();
  CLI::App* cmd = app.add_subcommand("submit", "Upload a mission folder and start a job on it");
  cmd->add_option("mission-dir", args->mission_dir, "Mission folder holding mission.yaml")
      ->required();
  cmd->add_option("--cad", args->cad, "CAD mesh of the structure (PLY, OBJ, STL, OFF)");
  cmd->add_option("--stages", args->stages, "Comma-separated stages to run")
      ->default_str(kDefaultStages);
  cmd->add_option("--set", args->assignments, "Stage option, stage.option=value (repeatable)");
  cmd->add_option("--name", args->name, "Mission name (default: mission.yaml's name)");
  cmd->add_option(
      "--cache-dir", args->cache_dir,
      "Folder for bundle tars and upload state (default $XDG_CACHE_HOME/keel or ~/.cache/keel)");
  cmd->add_flag("--wait", args->wait, "Watch the job until it ends; exit code tells how it ended");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress output on stderr");
  cmd->callback([&context, args] { context.exit_code = run_submit(context, *args); });
}

}  // namespace keel::client
