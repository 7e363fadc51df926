// Stage `refine`'s report.json builders for the solve: the solver's figures, the degenerate
// keyframes and the MAP noise it used (dvl_report.h, evaluation.h and self_check.h build the
// other sections).
#pragma once

#include <nlohmann/json.hpp>

#include <vector>

#include "core/time.h"
#include "worker/slam/refine_solver.h"

namespace keel::pipeline {

nlohmann::json solver_json(const slam::RefineSummary& summary);
// {count, ranges}: the runs of consecutive degenerate keyframes as stamp ranges.
nlohmann::json degenerate_json(const slam::RefineResult& result);
// The MAP noise the last pass used, as sigmas along the axes and the principal axes.
nlohmann::json map_noise_json(const slam::RefineResult& result, bool anchors);

// The runs of consecutive keyframes with flagged[k], as [{t_first_s, t_last_s, keyframes}].
nlohmann::json stamp_ranges(const std::vector<TimeNs>& t_ns, const std::vector<bool>& flagged);

}  // namespace keel::pipeline
