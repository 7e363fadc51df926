// Feature tracks across keyframes from verified pairwise matches: the connected components of
// the match graph over (keyframe, feature) nodes (union-find). A component that holds two
// features of the same keyframe is inconsistent (a wrong match somewhere) and is dropped.
#pragma once

#include <utility>
#include <vector>

namespace keel::ba {

struct PairMatches {
  int keyframe_a = 0;
  int keyframe_b = 0;
  std::vector<std::pair<int, int>> matches;  // (feature index in a, feature index in b)
};

struct TrackNode {
  int keyframe = 0;
  int feature = 0;
};

// `features_per_keyframe[k]` is the number of features of keyframe k. Tracks have at least
// `min_length` keyframes, nodes sorted by keyframe.
std::vector<std::vector<TrackNode>> build_tracks(const std::vector<PairMatches>& pairs,
                                                 const std::vector<int>& features_per_keyframe,
                                                 int min_length = 2);

}  // namespace keel::ba
