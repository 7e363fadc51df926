// Step 3 of stage `ba` with `tracks=ground_truth`: the mission's true feature tracks
// (truth.yaml `feature_tracks`, io/truth_tracks.h) at the keyframes.
#pragma once

#include <string>
#include <vector>

#include "worker/ba/ba_problem.h"
#include "worker/io/mission.h"

namespace keel::pipeline {

// The tracks of `camera` with at least two observations at keyframes, by landmark id. A row
// belongs to the keyframe within 1 ms of its stamp (stamps are printed with limited decimals);
// rows at no keyframe are left out.
std::vector<ba::FeatureTrack> ground_truth_tracks(const io::Mission& mission,
                                                  const std::string& camera,
                                                  const std::vector<ba::BaKeyframe>& keyframes);

}  // namespace keel::pipeline
