// The inspect report's comparison with truth (docs/artifacts.md: "with ground truth, each foreign
// object found or missed"): truth.yaml's `foreign_objects` (docs/mission-format.md "Ground
// truth") matched to the detected shapes.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

#include "worker/inspect/shape_report.h"

namespace keel::pipeline {

// The report's `truth`: each object of `truth_yaml` matched to its nearest shape (found when
// the shape's centroid is within the object's radius plus `match_distance_m` of its centre,
// then measured vs true height), and the shapes matching no object.
nlohmann::json truth_evaluation(const std::filesystem::path& truth_yaml,
                                const std::vector<inspect::ShapeSummary>& shapes,
                                double match_distance_m);

}  // namespace keel::pipeline
