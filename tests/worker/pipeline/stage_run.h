// Runs a pipeline stage on a mission folder the way the job runner does, recording the
// progress it reports.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

#include "worker/pipeline/stage.h"

namespace keel::pipeline::testing {

struct StageRun {
  StageResult result;
  std::vector<double> progress;
};

inline StageRun run_stage(Stage& stage, const std::filesystem::path& mission,
                          const nlohmann::json& options, const std::filesystem::path& work_dir) {
  std::filesystem::create_directories(work_dir);
  StageContext context;
  context.mission_dir = mission;
  context.work_dir = work_dir;
  context.options = options;
  StageRun run;
  context.progress = [&](double p) { run.progress.push_back(p); };
  run.result = stage.run(context);
  return run;
}

}  // namespace keel::pipeline::testing
