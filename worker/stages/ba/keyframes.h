// Step 2 of stage `ba`: a keyframe at each camera image, with its initial pose, servo angle,
// depth (Eq. 9) and image, and the odometry between consecutive keyframes (Eq. 11).
#pragma once

#include <nlohmann/json.hpp>

#include <vector>

#include "worker/ba/ba_problem.h"
#include "worker/io/mission_reader.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/ba/options.h"
#include "worker/stages/ba/sensors.h"

namespace keel::pipeline {

struct BaKeyframes {
  std::vector<ba::BaKeyframe> keyframes;
  std::vector<ba::BaOdometry> odometry;
  nlohmann::json report = nlohmann::json::object();  // the report's `input`: where each came from
};

// Initial poses are the recorded `odometry` corrected by the `map` keyframe poses (Algorithm 2
// of seed 000, as the map stage does), else whichever of the two the mission has. An image
// outside the poses' or the servo's span is skipped. Images are decoded only when
// `decode_images` (the SIFT frontend needs them).
BaKeyframes build_keyframes(const io::MissionReader& reader, const BaSensors& sensors,
                            const BaStageOptions& options, bool decode_images,
                            const StageContext& context);

}  // namespace keel::pipeline
