// `keel-worker run --mission DIR|TAR [--cad FILE] [--stages a,b] --out DIR [--set s.o=v]...`:
// the same JobRunner as `serve`, on local files, with no server. Artifacts and report.json
// go to --out. Exit codes: 0 done, 1 usage, 2 a stage failed, 130 interrupted (SIGINT).
#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "proto/calibration.h"
#include "proto/contract_error.h"
#include "proto/options.h"
#include "worker/main/commands.h"
#include "worker/main/stop_signal.h"
#include "worker/pipeline/bundle_unpack.h"
#include "worker/pipeline/job_runner.h"
#include "worker/pipeline/report.h"
#include "worker/pipeline/report_html.h"

namespace keel::worker {

namespace {

namespace fs = std::filesystem;

struct RunArgs {
  std::string mission;
  std::string cad;
  std::string stages;
  std::string out;
  std::vector<std::string> sets;
};

int usage_error(const std::string& message) {
  std::cerr << "keel-worker run: " << message << "\n";
  return kExitUsage;
}

// The stages to run: --stages, checked against what this worker has, or all of them but
// `compare` (which reads two jobs, not a mission: `keel-worker compare`).
std::vector<std::string> select_stages(const std::string& text) {
  const std::vector<std::string> available = pipeline::available_stages();
  if (text.empty()) {
    std::vector<std::string> stages;
    for (const auto& s : available)
      if (s != "compare") stages.push_back(s);
    return stages;
  }
  std::vector<std::string> stages = proto::parse_stage_list(text);
  for (const auto& stage : stages) {
    if (std::find(available.begin(), available.end(), stage) != available.end()) continue;
    std::string list;
    for (const auto& a : available) list += (list.empty() ? "" : ", ") + a;
    throw proto::ContractError("stage '" + stage +
                               "' is not built into this worker (available: " + list + ")");
  }
  return stages;
}

// Prints "[stage] NN%" whenever the whole percentage moves.
class ProgressPrinter {
 public:
  void operator()(const std::string& stage, double progress) {
    const int percent = static_cast<int>(std::floor(progress * 100.0));
    if (stage == stage_ && percent == percent_) return;
    stage_ = stage;
    percent_ = percent;
    std::cout << "[" << stage << "] " << percent << "%" << std::endl;
  }

 private:
  std::string stage_;
  int percent_ = -1;
};

int run_local(const RunArgs& args) {
  install_stop_signals();
  pipeline::JobSpec spec;
  try {
    spec.stages = select_stages(args.stages);
    for (const auto& assignment : args.sets)
      proto::apply_option_assignment(spec.options, assignment);
  } catch (const std::exception& e) {
    return usage_error(e.what());
  }
  if (spec.stages.empty()) return usage_error("this worker has no stages built in");
  for (const auto& item : spec.options.items())
    if (item.key() != proto::kCalibrationOption &&
        std::find(spec.stages.begin(), spec.stages.end(), item.key()) == spec.stages.end())
      std::cerr << "keel-worker run: warning: options for stage '" << item.key()
                << "', which does not run\n";

  std::error_code ec;
  if (!args.cad.empty() && !fs::is_regular_file(args.cad, ec))
    return usage_error("--cad " + args.cad + ": no such file");
  if (!fs::exists(args.mission, ec))
    return usage_error("--mission " + args.mission + ": not found");
  spec.work_dir = fs::absolute(args.out);
  fs::create_directories(spec.work_dir, ec);
  if (ec) return usage_error("--out " + args.out + ": " + ec.message());
  const fs::path report_path = spec.work_dir / pipeline::kReportFileName;
  fs::remove(report_path, ec);  // a report from an earlier run must not pass for this one's
  fs::remove(spec.work_dir / pipeline::kReportHtmlFileName, ec);

  try {
    if (fs::is_directory(args.mission)) {
      spec.mission_dir = pipeline::find_mission_root(fs::absolute(args.mission));
    } else {
      const fs::path unpacked = spec.work_dir / ".mission";
      fs::remove_all(unpacked, ec);
      spec.mission_dir = pipeline::unpack_bundle(args.mission, unpacked);
    }
  } catch (const std::exception& e) {
    std::cerr << "keel-worker run: " << e.what() << "\n";
    return kExitStageFailed;
  }
  if (!args.cad.empty()) spec.cad_path = fs::absolute(args.cad);

  spec.report_job = {{"id", "local"}, {"stages", spec.stages}, {"options", spec.options}};
  spec.report_mission = {{"path", spec.mission_dir.string()}, {"cad", spec.cad_path.string()}};

  ProgressPrinter printer;
  pipeline::JobHooks hooks;
  hooks.progress = [&](const std::string& stage, double p) { printer(stage, p); };
  hooks.log = [](const std::string& line) { std::cout << line << std::endl; };
  hooks.canceled = stop_requested;
  const pipeline::JobResult result = pipeline::JobRunner().run(spec, hooks);

  if (result.outcome == pipeline::JobOutcome::kCanceled) {
    std::cerr << "keel-worker run: interrupted during " << result.failed_stage << "\n";
    return kExitInterrupted;
  }
  if (!result.report_error.empty()) {
    std::cerr << "keel-worker run: " << result.report_error << "\n";
    return kExitStageFailed;
  }
  if (result.outcome == pipeline::JobOutcome::kFailed) {
    std::cerr << "keel-worker run: " << result.error << "\n";
    return kExitStageFailed;
  }
  std::cout << "report: " << report_path.string()
            << "\nreport.html: " << (spec.work_dir / pipeline::kReportHtmlFileName).string()
            << std::endl;
  return kExitOk;
}

}  // namespace

Subcommand add_run_command(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "Run stages locally on a mission, without a server");
  cmd->add_option("--mission", args->mission, "Mission folder (holding mission.yaml) or bundle tar")
      ->required();
  cmd->add_option("--cad", args->cad, "CAD mesh (PLY, OBJ, STL, OFF)");
  cmd->add_option("--stages", args->stages, "Comma-separated stages (default: all built in)");
  cmd->add_option("--out", args->out, "Folder for the artifacts and report.json")->required();
  cmd->add_option("--set", args->sets, "Stage option, stage.option=value (repeatable)")
      ->allow_extra_args(false);
  return {cmd, [args] { return run_local(*args); }};
}

}  // namespace keel::worker
