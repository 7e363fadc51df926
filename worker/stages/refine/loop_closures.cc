// Step 5 of stage `refine`: loops.csv's loop closures L_pq (seed 000 Eq. (1)) whose stamps
// both match a keyframe; the others are counted and warned about.
#include "worker/stages/refine/inputs.h"

namespace keel::pipeline {

void loop_closures(const io::MissionReader& reader, const RefineStageOptions& options,
                   const slam::RefineOptions& solver_options, Inputs& in) {
  in.report["keyframes"]["used"] = in.solver.keyframes.size();
  if (!options.loop_closures) {
    in.report["loop_closures"] = {{"used", 0}, {"disabled", true}};
    return;
  }
  const auto loops = reader.read_loop_closures();
  const TimeNs tolerance = seconds_to_ns(solver_options.measurement_time_tolerance_s);
  size_t skipped = 0;
  for (const auto& loop : loops) {
    if (find_keyframe(in.solver.keyframes, loop.t_i_ns, tolerance) < 0 ||
        find_keyframe(in.solver.keyframes, loop.t_j_ns, tolerance) < 0) {
      ++skipped;
      continue;
    }
    in.solver.loop_closures.push_back(
        {loop.t_i_ns, loop.t_j_ns, loop.T_body_i_body_j,
         slam::isotropic_information(loop.sigma_t_m, loop.sigma_r_rad)});
  }
  in.report["loop_closures"] = {{"count", loops.size()},
                                {"used", in.solver.loop_closures.size()},
                                {"skipped_no_keyframe", skipped}};
  if (skipped > 0)
    in.warnings.push_back(std::to_string(skipped) +
                          " loop closures match no keyframe stamp and were left out");
}

}  // namespace keel::pipeline
