#include "worker/stages/refine/solves.h"

#include <string>

namespace keel::pipeline {

namespace {

void log_solve(StageContext& context, const std::string& what, const slam::RefineResult& r) {
  context.log("refine: solved " + what + " in " + std::to_string(r.summary.total_time_s) + " s, " +
              std::to_string(r.summary.iterations) + " iterations, cost " +
              std::to_string(r.summary.initial_cost) + " -> " +
              std::to_string(r.summary.final_cost));
}

}  // namespace

Solves solve(const slam::RefineInput& input, slam::RefineOptions solver_options,
             const RefineStageOptions& options, bool has_truth, StageContext& context) {
  const bool second_solve = options.dvl && has_truth && options.compare_without_dvl;
  Solves out;
  if (options.dvl) {
    solver_options.use_dvl = true;
    out.with_dvl = slam::refine_trajectory(input, solver_options);
    log_solve(context, "with DVL", *out.with_dvl);
    context.progress(second_solve ? 0.6 : 0.9);
    context.check_canceled();
  }
  if (!options.dvl || second_solve) {
    slam::RefineOptions no_dvl = solver_options;
    no_dvl.use_dvl = false;
    slam::RefineInput without = input;
    without.dvl.clear();
    out.without_dvl = slam::refine_trajectory(without, no_dvl);
    log_solve(context, "without DVL", *out.without_dvl);
    context.progress(0.9);
    context.check_canceled();
  }
  return out;
}

}  // namespace keel::pipeline
