// Feature tracks of a mission's ground truth (docs/mission-format.md "Ground truth"): truth.yaml's
// `feature_tracks: {<camera>: <csv>}` names, per camera, a CSV `id,t,u,v` of the true pixel of
// landmark `id` in the image at `t`. keel-sim writes them; the `ba` stage can use them instead of
// its SIFT frontend (`ba.tracks=ground_truth`).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/time.h"

namespace keel::io {

struct TruthTrackPixel {
  int64_t landmark_id = 0;
  TimeNs t_ns = 0;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // u, v
};

// The CSV that `truth_yaml` names for `camera` (relative to truth.yaml's folder); nullopt when
// it names none.
std::optional<std::filesystem::path> truth_tracks_file(const std::filesystem::path& truth_yaml,
                                                       const std::string& camera);

// Every row, in the file's order. Fails naming the file (and line) when it cannot be opened,
// lacks the header or holds a row that is not four numbers.
std::vector<TruthTrackPixel> read_truth_tracks(const std::filesystem::path& csv);

}  // namespace keel::io
