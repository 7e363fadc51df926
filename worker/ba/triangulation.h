// Initial landmark positions from feature tracks and the initial camera poses: linear
// multi-view triangulation (DLT, Hartley & Zisserman Sec. 12.2) in normalised image
// coordinates, over every top and bottom observation of the track, then sanity gates.
// Not in seed 001, whose online SLAM supplies the landmarks.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <vector>

#include "worker/ba/ba_options.h"
#include "worker/ba/ba_problem.h"

namespace keel::ba {

// `T_world_camera[k]` is keyframe k's top camera. Returns nullopt when the track has fewer
// than two rays, the point is behind or too close to / far from a camera, reprojects worse
// than the gate, or (without stereo observations) the rays are closer than min_parallax.
std::optional<Eigen::Vector3d> triangulate_track(const FeatureTrack& track,
                                                 const std::vector<Pose3>& T_world_camera,
                                                 const BaRig& rig,
                                                 const TriangulationOptions& options);

// The depth and reprojection gates of triangulate_track() for a landmark already placed (e.g.
// after the SLAM initialisation): in front of every observing camera within
// [min_depth_m, max_depth_m] and reprojecting within max_reprojection_px.
bool landmark_within_gates(const Eigen::Vector3d& point, const FeatureTrack& track,
                           const std::vector<Pose3>& T_world_camera, const BaRig& rig,
                           double max_reprojection_px, const TriangulationOptions& options);

// Per observation of `track`, the larger of its top and (stereo) bottom reprojection errors in
// pixels; infinity where the point is not in front of that camera.
std::vector<double> observation_reprojection_errors_px(const Eigen::Vector3d& point,
                                                       const FeatureTrack& track,
                                                       const std::vector<Pose3>& T_world_camera,
                                                       const BaRig& rig);

// Robust per-axis pixel noise sigma of landmarks fitted to their tracks (points[k] to
// tracks[k]): the median over images (a stereo observation's two cameras apart) of the
// reprojection error norm, each scaled by sqrt(m / (m - 3)) for its track's m image
// coordinates (a fitted point absorbs 3 of them, so a two-view track's residuals are half the
// noise), divided by sqrt(2 ln 2), the median of a unit 2-D Gaussian's norm (Rayleigh). The
// median ignores wrong matches. Infinity when no image has a finite error; throws
// std::invalid_argument when points and tracks differ in number.
double robust_pixel_sigma_px(const std::vector<Eigen::Vector3d>& points,
                             const std::vector<FeatureTrack>& tracks,
                             const std::vector<Pose3>& T_world_camera, const BaRig& rig);

// Post-initialisation gate of one placed landmark: removes from `track` the observations
// reprojecting further than gate_px, then keeps the landmark (returns true) only if at least
// two (stereo track) or options.min_monocular_views (monocular track) observations remain and
// it passes landmark_within_gates() with gate_px.
bool gate_landmark_observations(const Eigen::Vector3d& point, FeatureTrack& track,
                                const std::vector<Pose3>& T_world_camera, const BaRig& rig,
                                double gate_px, const TriangulationOptions& options);

}  // namespace keel::ba
