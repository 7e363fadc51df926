#include "worker/ba/model_assisted_ba.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "worker/ba/ba_graph.h"
#include "worker/ba/feature_frontend.h"
#include "worker/ba/gicp_alignment.h"
#include "core/mesh_query.h"
#include "worker/ba/rig_geometry.h"
#include "worker/ba/triangulation.h"
#include "core/suitesparse_memory.h"

namespace keel::ba {
namespace {

// Step 2.
std::vector<FeatureTrack> feature_tracks(const BaProblem& problem, const BaOptions& options,
                                         BaResult& result) {
  if (!problem.tracks.empty()) return problem.tracks;
  FrontendOutput frontend = run_frontend(problem.keyframes, problem.rig, options.frontend);
  result.frontend = frontend.stats;
  return std::move(frontend.tracks);
}

// Step 3.
void triangulate(const std::vector<FeatureTrack>& tracks, const BaProblem& problem,
                 const BaOptions& options, BaInitialState& state) {
  const ServoMount mount = servo_mount(problem.rig);
  std::vector<Pose3> T_world_camera;
  for (size_t i = 0; i < state.T_world_vehicle.size(); ++i) {
    T_world_camera.push_back(world_camera_pose(state.T_world_vehicle[i], state.servo_angle_rad[i],
                                               mount, state.T_servo_camera));
  }
  for (const FeatureTrack& track : tracks) {
    const auto point = triangulate_track(track, T_world_camera, problem.rig, options.triangulation);
    if (!point) continue;
    state.tracks.push_back(track);
    state.landmarks_world.push_back(*point);
  }
}

// Step 4, after the model-free solve. The poses now agree with the images, so each
// observation must reproject within a chi-square gate (triangulation.h,
// gate_landmark_observations) and a monocular landmark keeps at least min_monocular_views of
// them; then the triangulation's depth gate runs again on the refined state. A wrong match
// (SIFT on repetitive hull texture) can drift out of the depth range there: one left 1e8 m
// away made the surface factors' cost 1e19 and `geva` run 1,400 s on keel-sim hauv-hull with
// frontend tracks. The gate's sigma is the measured pixel noise, never above Eq. (12)-(13)'s
// sigma_c: the paper's 2 px is a model figure, keel-sim hauv-hull's images measure 0.14 px, and
// a 7.4 px gate there kept wrong views that put the 0.110 m cylinder at 0.181 m (seed 1).
void drop_inconsistent_landmarks(const BaProblem& problem, const BaOptions& options,
                                 BaInitialState& state, BaResult& result) {
  const ServoMount mount = servo_mount(problem.rig);
  std::vector<Pose3> T_world_camera;
  for (size_t i = 0; i < state.T_world_vehicle.size(); ++i) {
    T_world_camera.push_back(world_camera_pose(state.T_world_vehicle[i], state.servo_angle_rad[i],
                                               mount, state.T_servo_camera));
  }
  double sigma_px = options.pixel_sigma;
  if (options.triangulation.measure_pixel_sigma) {
    const double measured_px = std::max(
        options.triangulation.min_pixel_sigma_px,
        robust_pixel_sigma_px(state.landmarks_world, state.tracks, T_world_camera, problem.rig));
    sigma_px = std::min(sigma_px, measured_px);
  }
  const double gate_px = options.triangulation.post_initialisation_gate_sigmas * sigma_px;
  result.post_initialisation_gate_px = gate_px;
  size_t kept = 0;
  for (size_t k = 0; k < state.tracks.size(); ++k) {
    FeatureTrack& track = state.tracks[k];
    const size_t views_before = track.observations.size();
    const bool keep = gate_landmark_observations(state.landmarks_world[k], track, T_world_camera,
                                                 problem.rig, gate_px, options.triangulation);
    result.observations_dropped_after_initialisation +=
        static_cast<int>(views_before - track.observations.size());
    if (!keep) continue;
    if (kept != k) {  // a self-move would empty the track's observations
      state.tracks[kept] = std::move(state.tracks[k]);
      state.landmarks_world[kept] = state.landmarks_world[k];
    }
    ++kept;
  }
  result.landmarks_dropped_after_initialisation = static_cast<int>(state.tracks.size() - kept);
  state.tracks.resize(kept);
  state.landmarks_world.resize(kept);
}

// Step 5: DVL returns in the world frame from the SLAM-corrected poses.
std::vector<Eigen::Vector3d> dvl_returns_world(const BaProblem& problem,
                                               const BaInitialState& state) {
  const ServoMount mount = servo_mount(problem.rig);
  std::vector<Eigen::Vector3d> points;
  for (const DvlRange& r : problem.dvl_ranges) {
    const Pose3 T_world_dvl = state.T_world_vehicle[r.keyframe] *
                              mount.T_vehicle_servo(state.servo_angle_rad[r.keyframe]) *
                              problem.rig.T_servo_dvl;
    points.push_back(T_world_dvl * (r.range_m * r.direction_dvl));
  }
  return points;
}

// Step 6.
void gate_beams(const BaProblem& problem, const MeshQuery& mesh, const BaOptions& options,
                BaInitialState& state) {
  const ServoMount mount = servo_mount(problem.rig);
  for (const DvlRange& r : problem.dvl_ranges) {
    const DvlBeam beam = make_dvl_beam(problem.rig.T_servo_dvl, r.direction_dvl, r.range_m);
    const auto range = predict_dvl_range(mesh, mount, beam, state.T_world_vehicle[r.keyframe],
                                         state.servo_angle_rad[r.keyframe], state.T_world_model,
                                         options.dvl_max_range_m);
    if (!range || std::abs(*range - r.range_m) > options.dvl_gate_m) continue;
    state.beams.push_back(beam);
    state.beam_keyframe.push_back(r.keyframe);
  }
}

}  // namespace

BaResult run_model_assisted_ba(const BaProblem& problem, const BaOptions& options) {
  validate(options);  // step 1
  validate(problem);
  use_aligned_suitesparse_memory();  // the same bits wherever its fronts land
  const MeshQuery mesh(problem.cad_mesh);
  BaResult result;
  BaInitialState state;
  for (const BaKeyframe& k : problem.keyframes) {
    state.T_world_vehicle.push_back(k.T_world_vehicle);
    state.servo_angle_rad.push_back(k.servo_angle_rad);
  }
  state.T_servo_camera = problem.rig.T_servo_camera;

  const std::vector<FeatureTrack> tracks = feature_tracks(problem, options, result);  // step 2
  result.tracks_in = static_cast<int>(tracks.size());
  triangulate(tracks, problem, options, state);  // step 3
  result.landmarks_triangulated = static_cast<int>(state.tracks.size());
  if (state.tracks.empty()) {
    throw std::invalid_argument(
        "ba: no feature track could be triangulated from the initial "
        "poses (" +
        std::to_string(tracks.size()) + " tracks)");
  }

  if (options.slam_initialisation) {  // step 4
    result.initialisation = refine_initial_state(problem, mesh, state, options);
    drop_inconsistent_landmarks(problem, options, state, result);
    if (state.tracks.empty())
      throw std::invalid_argument("ba: no landmark survived the SLAM initialisation");
  }

  const GicpAlignment gicp = align_dvl_returns_to_model(  // step 5
      dvl_returns_world(problem, state), problem.cad_mesh, problem.T_world_model_guess,
      options.gicp);
  result.gicp_ran = gicp.ran;
  result.gicp_converged = gicp.converged;
  result.gicp_fitness = gicp.fitness;
  state.T_world_model = gicp.T_world_model;
  result.T_world_model_initial = gicp.T_world_model;

  gate_beams(problem, mesh, options, state);  // step 6
  result.dvl_ranges_in = static_cast<int>(problem.dvl_ranges.size());
  result.dvl_ranges_used = static_cast<int>(state.beams.size());

  for (BaMode mode : options.modes) {  // step 7
    result.modes.push_back(solve_ba_mode(problem, mesh, state, mode, options));
  }
  return result;
}

}  // namespace keel::ba
