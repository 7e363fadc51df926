// Step 4 of stage `ba`: the DVL range returns of Eq. (14) at the keyframes.
#pragma once

#include <vector>

#include "proto/mission_manifest.h"
#include "worker/ba/ba_problem.h"
#include "worker/io/mission_reader.h"

namespace keel::pipeline {

// Each keyframe takes the 4-beam ping of `dvl` nearest its image if within `max_dt_s`, one
// return per beam that has a range (a beam without a return is NaN in the stream).
std::vector<ba::DvlRange> dvl_ranges_at_keyframes(const io::MissionReader& reader,
                                                  const proto::SensorSpec& dvl,
                                                  const std::vector<ba::BaKeyframe>& keyframes,
                                                  double max_dt_s);

}  // namespace keel::pipeline
