// Step 2 of the compare stage, first part: B's maps moved into A's frame. The global
// registration on stable structure runs once, on the first map compared, and its transform
// moves every map of B; then, with tiles, each tile of B is registered on its own
// (compare/local_registration.h), two surveys' maps each carrying their own trajectory's errors.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "core/pose.h"
#include "worker/pipeline/stage.h"
#include "worker/stages/compare/options.h"

namespace keel::pipeline {

struct MapAlignment {
  bool registered = false;
  Pose3 T_a_b = Pose3::Identity();  // maps B's points into A's frame
  nlohmann::json registration;      // the report's "registration", once registered
};

// Moves `b` onto `a` (nothing with options.register_maps false); returns the map's
// "local_registration" section, null without it.
nlohmann::json align_map(StageContext& context, const CompareStageOptions& options,
                         const std::string& map, const std::vector<Eigen::Vector3f>& a,
                         std::vector<Eigen::Vector3f>* b, MapAlignment* alignment);

}  // namespace keel::pipeline
