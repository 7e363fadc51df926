// `keel-worker compare --a DIR --b DIR --out DIR [--set compare.x=v]...`: the `compare` stage on
// two local job folders (the --out of two `keel-worker run`s, or two `keel fetch`es), A the
// earlier, B the later. Artifacts (change_<map>.drc, changes.json, ...) and report.json go to
// --out. Exit codes: 0 done, 1 usage, 2 the comparison failed (or was refused), 130 interrupted.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "proto/options.h"
#include "worker/main/commands.h"
#include "worker/main/stop_signal.h"
#include "worker/pipeline/job_runner.h"
#include "worker/pipeline/report.h"

namespace keel::worker {
namespace {

namespace fs = std::filesystem;

struct CompareArgs {
  std::string a, b, out;
  std::vector<std::string> sets;
};

// The job record of a local folder: report.json's "job" section (id, stages, options), with
// the state a finished run has.
pipeline::InputJob input_job(const std::string& dir, const char* label) {
  pipeline::InputJob job;
  job.dir = fs::absolute(dir);
  std::ifstream in(job.dir / pipeline::kReportFileName);
  if (!in) throw std::runtime_error("--" + std::string(label) + " " + dir + ": no report.json");
  nlohmann::json report;
  try {
    report = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error("--" + std::string(label) + " " + dir +
                             ": report.json is not valid JSON: " + e.what());
  }
  job.job = report.value("job", nlohmann::json::object());
  job.job["id"] = dir;
  job.job["state"] = "succeeded";
  if (report.contains("mission") && report["mission"].contains("path"))
    job.job["mission_id"] = report["mission"]["path"];
  return job;
}

int run_compare(const CompareArgs& args) {
  install_stop_signals();
  pipeline::JobSpec spec;
  spec.stages = {"compare"};
  try {
    for (const auto& assignment : args.sets)
      proto::apply_option_assignment(spec.options, assignment);
    spec.input_jobs = {input_job(args.a, "a"), input_job(args.b, "b")};
  } catch (const std::exception& e) {
    std::cerr << "keel-worker compare: " << e.what() << "\n";
    return kExitUsage;
  }
  std::error_code ec;
  spec.work_dir = fs::absolute(args.out);
  fs::create_directories(spec.work_dir, ec);
  if (ec) {
    std::cerr << "keel-worker compare: --out " << args.out << ": " << ec.message() << "\n";
    return kExitUsage;
  }
  const fs::path report_path = spec.work_dir / pipeline::kReportFileName;
  fs::remove(report_path, ec);

  spec.report_job = {{"id", "local"},
                     {"stages", spec.stages},
                     {"options", spec.options},
                     {"job_a", args.a},
                     {"job_b", args.b}};

  pipeline::JobHooks hooks;
  hooks.log = [](const std::string& line) { std::cout << line << std::endl; };
  hooks.canceled = stop_requested;
  const pipeline::JobResult result = pipeline::JobRunner().run(spec, hooks);
  if (result.outcome == pipeline::JobOutcome::kCanceled) return kExitInterrupted;
  if (result.outcome == pipeline::JobOutcome::kFailed) {
    std::cerr << "keel-worker compare: " << result.error << "\n";
    return kExitStageFailed;
  }
  if (!result.report_error.empty()) {
    std::cerr << "keel-worker compare: " << result.report_error << "\n";
    return kExitStageFailed;
  }
  std::cout << "report: " << report_path.string() << std::endl;
  return kExitOk;
}

}  // namespace

Subcommand add_compare_command(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Compare two local job folders (A earlier, B later): maps, hulls, runs");
  cmd->add_option("--a", args->a, "Folder of job A (artifacts and report.json)")->required();
  cmd->add_option("--b", args->b, "Folder of job B")->required();
  cmd->add_option("--out", args->out, "Folder for the comparison's artifacts")->required();
  cmd->add_option("--set", args->sets, "compare.option=value (repeatable)")
      ->allow_extra_args(false);
  return {cmd, [args] { return run_compare(*args); }};
}

}  // namespace keel::worker
