// Step 6 of stage `refine`: the batch solve with DVL fusion (seed 000 Sec. IV) and, when ground
// truth exists, a second solve without it, so the report can set them side by side (Table II).
#pragma once

#include <optional>

#include "worker/pipeline/stage.h"
#include "worker/slam/refine_solver.h"
#include "worker/stages/refine/options.h"

namespace keel::pipeline {

struct Solves {
  std::optional<slam::RefineResult> with_dvl;     // with DVL fusion (options.dvl)
  std::optional<slam::RefineResult> without_dvl;  // without: the only one, or Table II's column
  // The solve written to trajectory_refined.tum.
  const slam::RefineResult& written() const { return with_dvl ? *with_dvl : *without_dvl; }
  bool both() const { return with_dvl && without_dvl; }
};

// The solver has no iteration callback, so cancellation is checked between the solves.
Solves solve(const slam::RefineInput& input, slam::RefineOptions solver_options,
             const RefineStageOptions& options, bool has_truth, StageContext& context);

}  // namespace keel::pipeline
