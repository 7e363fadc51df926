// Visual frontend of Sec. 2.7, seed 001: SIFT features [41], nearest-neighbour descriptor
// matching with Lowe's ratio test, geometric verification by RANSAC, and tracks across
// keyframes. Monocular: an essential matrix per keyframe pair, RANSAC scored by the Sampson
// (epipolar) distance (OpenCV's five-point findEssentialMat, whose RANSAC error is the
// Sampson distance). Stereo: features matched between the rectified top and bottom images
// are triangulated, and matches between keyframes must agree with one rigid motion of those
// points (rigid_ransac.h). OpenCV stays in the .cc.
#pragma once

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

}  // namespace keel::ba
