// Visual frontend of Sec. 2.7, seed 001: SIFT features [41], nearest-neighbour descriptor
// matching with Lowe's ratio test, geometric verification by RANSAC, and tracks across
// keyframes. Monocular: an essential matrix per keyframe pair, RANSAC scored by the Sampson
// (epipolar) distance (OpenCV's five-point findEssentialMat, whose RANSAC error is the
// Sampson distance). Stereo: features matched between the rectified top and bottom images
// are triangulated, and matches between keyframes must agree with one rigid motion of those
// points (rigid_ransac.h). OpenCV stays in the .cc.
#pragma once

#include <Eigen/Core>

#include <vector>

#include "worker/ba/ba_options.h"
#include "worker/ba/ba_problem.h"
#include "worker/ba/ba_result.h"

namespace keel::ba {

struct FrontendOutput {
  std::vector<FeatureTrack> tracks;  // landmark ids 0..n-1
  BaFrontendStats stats;
};

// Uses keyframes[k].image_top (and image_bottom when rig.camera_bottom is set). Keyframes
// without images take part in no track. Throws std::invalid_argument naming the keyframe
// when a stereo rig lacks a bottom image next to a top one.
FrontendOutput run_frontend(const std::vector<BaKeyframe>& keyframes, const BaRig& rig,
                            const FrontendOptions& options);

// Monocular geometric verification of one keyframe pair (matched pixels_a[i] <-> pixels_b[i]):
// inliers of a RANSAC essential matrix (Sampson distance <= essential_threshold_px) that, when
// options.gate_two_view_depth and baseline_m > 0, also triangulate in front of both cameras
// between min_depth_m and max_depth_m, with E's relative pose scaled to baseline_m (the
// initial poses' camera-centre distance). Fewer than 5 matches: none verified. Throws
// std::invalid_argument when the two lists differ in size.
std::vector<bool> verify_monocular_matches(const std::vector<Eigen::Vector2d>& pixels_a,
                                           const std::vector<Eigen::Vector2d>& pixels_b,
                                           const PinholeCamera& camera, double baseline_m,
                                           const FrontendOptions& options);

}  // namespace keel::ba
