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

}  // namespace keel::ba
