// Step 4 of stage `refine`: the odometry edges L_ij between consecutive keyframes (seed 000
// Eq. (1)), from the recorded odometry or, when the mission has none, GICP between keyframe
// scans; optionally widened by their disagreement with the MAP poses.
#include <algorithm>
#include <limits>
#include <stdexcept>

#include "worker/slam/gicp_odometry.h"
#include "worker/slam/odometry_noise_from_map.h"
#include "worker/stages/refine/inputs.h"

namespace keel::pipeline {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

void widen_by_map_disagreement(Inputs& in) {
  const auto rms = slam::widen_by_map_disagreement(in.solver.keyframes, in.solver.odometry);
  if (!rms) return;
  const auto& r = *rms;
  in.report["odometry"]["disagreement_with_map_rms"] = {
      {"translation_m", {r[0], r[1], r[2]}},
      {"rotation_deg", {r[3] * kRadToDeg, r[4] * kRadToDeg, r[5] * kRadToDeg}}};
}

// The recorded odometry at the keyframe stamps; keyframes outside it are dropped.
void recorded_odometry(const io::MissionReader& reader, const RefineStageOptions& options,
                       Inputs& in) {
  const Trajectory odometry = reader.read_trajectory("odometry");
  if (odometry.size() < 2)
    throw std::runtime_error("trajectories.odometry: expected at least 2 poses, found " +
                             std::to_string(odometry.size()));
  std::vector<bool> keep(in.solver.keyframes.size());
  for (size_t k = 0; k < keep.size(); ++k)
    keep[k] = in.solver.keyframes[k].t_ns >= odometry.front().t_ns &&
              in.solver.keyframes[k].t_ns <= odometry.back().t_ns;
  const size_t before = in.solver.keyframes.size();
  in.solver.keyframes = select(in.solver.keyframes, keep);
  require_keyframes(in.solver.keyframes, "inside the span of trajectories.odometry");
  std::vector<TimeNs> stamps;
  for (const auto& p : in.solver.keyframes) stamps.push_back(p.t_ns);
  in.solver.odometry =
      slam::relative_poses_from_trajectory(odometry, stamps, options.recorded_odometry_noise);
  in.report["odometry"] = span_json(odometry.front().t_ns, odometry.back().t_ns);
  if (options.odometry_noise_from_map) widen_by_map_disagreement(in);
  in.report["odometry"]["source"] = "recorded";
  in.report["odometry"]["poses"] = odometry.size();
  in.report["odometry"]["edges"] = in.solver.odometry.size();
  in.report["keyframes"]["dropped_outside_odometry"] = before - in.solver.keyframes.size();
}

// GICP between the keyframe scans of the lidar (the scan nearest each keyframe, within the
// solver's time tolerance); keyframes without a scan are dropped.
void gicp_odometry(const io::MissionReader& reader, const RefineStageOptions& options,
                   const slam::RefineOptions& solver_options, StageContext& context, Inputs& in) {
  const proto::SensorSpec* lidar = pick_sensor(reader.manifest(), options.lidar_sensor,
                                               proto::SensorType::kLidar, "lidar_sensor");
  if (!lidar)
    throw std::runtime_error(
        "refine needs odometry: the mission has neither trajectories.odometry nor a lidar "
        "sensor for GICP scan matching");
  const std::optional<Pose3> T_body_lidar = reader.extrinsic(lidar->name);
  if (!T_body_lidar)
    throw std::runtime_error("sensor '" + lidar->name +
                             "': no T_body_sensor (neither in mission.yaml nor /tf_static); "
                             "GICP odometry needs it");
  const Trajectory& keyframes = in.solver.keyframes;
  const TimeNs tolerance = seconds_to_ns(solver_options.measurement_time_tolerance_s);
  std::vector<PointCloud> scans(keyframes.size());
  std::vector<TimeNs> best_dt(keyframes.size(), std::numeric_limits<TimeNs>::max());
  auto source = reader.open_scans(lidar->name);
  const size_t total = source->size();
  size_t read = 0;
  PointCloud cloud;
  while (true) {
    context.check_canceled();
    if (!source->next(cloud)) break;
    ++read;
    const long k = find_keyframe(keyframes, cloud.t_ns, tolerance);
    if (k >= 0 && std::abs(cloud.t_ns - keyframes[k].t_ns) < best_dt[k]) {
      best_dt[k] = std::abs(cloud.t_ns - keyframes[k].t_ns);
      scans[k] = cloud;
      scans[k].t_ns = keyframes[k].t_ns;
    }
    if (total > 0) context.progress(0.15 + 0.15 * static_cast<double>(read) / total);
  }
  std::vector<bool> keep(keyframes.size());
  std::vector<PointCloud> kept_scans;
  std::vector<Pose3> initial;
  for (size_t k = 0; k < keyframes.size(); ++k) {
    keep[k] = best_dt[k] != std::numeric_limits<TimeNs>::max();
    if (!keep[k]) continue;
    kept_scans.push_back(std::move(scans[k]));
    initial.push_back(keyframes[k].T_world_body);
  }
  const size_t before = keyframes.size();
  in.solver.keyframes = select(keyframes, keep);
  require_keyframes(in.solver.keyframes, "with a scan of '" + lidar->name + "'");
  context.check_canceled();
  in.solver.odometry = slam::relative_poses_from_scans(kept_scans, *T_body_lidar, initial);
  in.report["odometry"] = {{"source", "gicp"},
                           {"sensor", lidar->name},
                           {"scans_read", read},
                           {"edges", in.solver.odometry.size()}};
  // The point-to-plane information treats neighbouring residuals as independent and is far
  // too confident (millimetres); the disagreement with the MAP increments is the honest figure.
  if (options.odometry_noise_from_map) widen_by_map_disagreement(in);
  // A registration that did not converge or failed the outlier gate carries no information.
  // It is left out rather than passed on as a zero-information edge: that would flag its
  // keyframe degenerate, and the paper's zeroed biases there (Sec. IV-B), chained to the rest
  // by the bias random walks, would pin b^a to zero over the whole mission.
  const size_t matched = in.solver.odometry.size();
  auto& edges = in.solver.odometry;
  edges.erase(
      std::remove_if(edges.begin(), edges.end(),
                     [](const slam::RelativePoseMeasurement& m) { return m.information.isZero(); }),
      edges.end());
  in.report["odometry"]["edges"] = edges.size();
  in.report["odometry"]["edges_rejected"] = matched - edges.size();
  in.report["keyframes"]["dropped_without_scan"] = before - in.solver.keyframes.size();
}

}  // namespace

void odometry_edges(const io::MissionReader& reader, const RefineStageOptions& options,
                    const slam::RefineOptions& solver_options, StageContext& context, Inputs& in) {
  const bool recorded = reader.has_trajectory("odometry");
  if (options.odometry == "recorded" && !recorded)
    throw std::runtime_error(
        "options.refine.odometry=recorded, but mission.yaml has no trajectories.odometry");
  if (options.odometry == "gicp" || (options.odometry == "auto" && !recorded))
    gicp_odometry(reader, options, solver_options, context, in);
  else
    recorded_odometry(reader, options, in);
}

}  // namespace keel::pipeline
