#include "worker/ba/track_builder.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

namespace keel::ba {
namespace {

class UnionFind {
 public:
  explicit UnionFind(size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  size_t find(size_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];  // path halving
    return x;
  }
  void unite(size_t a, size_t b) { parent_[find(a)] = find(b); }

 private:
  std::vector<size_t> parent_;
};

}  // namespace

std::vector<std::vector<TrackNode>> build_tracks(const std::vector<PairMatches>& pairs,
                                                 const std::vector<int>& features_per_keyframe,
                                                 int min_length) {
  std::vector<size_t> offset(features_per_keyframe.size() + 1, 0);
  for (size_t k = 0; k < features_per_keyframe.size(); ++k) {
    offset[k + 1] = offset[k] + features_per_keyframe[k];
  }
  const auto node = [&](int keyframe, int feature) {
    if (keyframe < 0 || keyframe >= static_cast<int>(features_per_keyframe.size()) || feature < 0 ||
        feature >= features_per_keyframe[keyframe]) {
      throw std::out_of_range("build_tracks: match references a missing feature");
    }
    return offset[keyframe] + feature;
  };
  UnionFind sets(offset.back());
  std::vector<bool> matched(offset.back(), false);
  for (const PairMatches& p : pairs) {
    for (const auto& [fa, fb] : p.matches) {
      const size_t a = node(p.keyframe_a, fa), b = node(p.keyframe_b, fb);
      sets.unite(a, b);
      matched[a] = matched[b] = true;
    }
  }
  std::unordered_map<size_t, std::vector<TrackNode>> components;
  for (size_t k = 0; k < features_per_keyframe.size(); ++k) {
    for (int f = 0; f < features_per_keyframe[k]; ++f) {
      const size_t id = offset[k] + f;
      if (matched[id]) components[sets.find(id)].push_back({static_cast<int>(k), f});
    }
  }
  std::vector<std::vector<TrackNode>> tracks;
  for (auto& [root, nodes] : components) {
    // Nodes were appended in keyframe order; a repeated keyframe means a conflict.
    bool consistent = true;
    for (size_t i = 1; i < nodes.size(); ++i)
      consistent &= nodes[i].keyframe != nodes[i - 1].keyframe;
    if (consistent && static_cast<int>(nodes.size()) >= min_length)
      tracks.push_back(std::move(nodes));
  }
  // Deterministic order regardless of the hash map: by first node.
  std::sort(tracks.begin(), tracks.end(), [](const auto& a, const auto& b) {
    return std::make_pair(a[0].keyframe, a[0].feature) <
           std::make_pair(b[0].keyframe, b[0].feature);
  });
  return tracks;
}

}  // namespace keel::ba
