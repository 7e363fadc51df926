#include "worker/stages/ingest/mission_report.h"

namespace keel::pipeline {

nlohmann::json trajectory_report(const Trajectory& trajectory, const IngestOptions& options,
                                 const std::string& name, nlohmann::json& warnings) {
  std::vector<TimeNs> stamps;
  double path_length_m = 0.0;
  for (size_t i = 0; i < trajectory.size(); ++i) {
    stamps.push_back(trajectory[i].t_ns);
    if (i > 0)
      path_length_m +=
          (trajectory[i].T_world_body.translation() - trajectory[i - 1].T_world_body.translation())
              .norm();
  }
  nlohmann::json r = stamp_report(stamps, 0.0, options, "trajectories." + name, warnings);
  r["path_length_m"] = path_length_m;
  return r;
}

}  // namespace keel::pipeline
