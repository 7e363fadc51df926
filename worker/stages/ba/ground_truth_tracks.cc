#include "worker/stages/ba/ground_truth_tracks.h"

#include <cstdlib>
#include <map>

#include "proto/contract_error.h"
#include "worker/io/truth_tracks.h"

namespace keel::pipeline {

std::vector<ba::FeatureTrack> ground_truth_tracks(const io::Mission& mission,
                                                  const std::string& camera,
                                                  const std::vector<ba::BaKeyframe>& keyframes) {
  if (mission.ground_truth_path.empty())
    throw proto::ContractError(
        "options.ba.tracks: 'ground_truth' needs the mission's ground_truth: truth.yaml");
  const auto csv = io::truth_tracks_file(mission.ground_truth_path, camera);
  if (!csv)
    throw proto::ContractError("options.ba.tracks: " + mission.ground_truth_path.string() +
                               " has no feature_tracks." + camera);
  std::map<TimeNs, int> keyframe_of;
  for (size_t i = 0; i < keyframes.size(); ++i) keyframe_of[keyframes[i].t_ns] = int(i);
  std::map<int64_t, ba::FeatureTrack> tracks;
  constexpr TimeNs kMatchNs = 1000000;
  for (const io::TruthTrackPixel& row : io::read_truth_tracks(*csv)) {
    auto it = keyframe_of.lower_bound(row.t_ns - kMatchNs);
    if (it == keyframe_of.end() || std::llabs(it->first - row.t_ns) > kMatchNs) continue;
    ba::FeatureObservation o;
    o.keyframe = it->second;
    o.pixel = row.pixel;
    auto& track = tracks[row.landmark_id];
    track.landmark_id = row.landmark_id;
    track.observations.push_back(o);
  }
  std::vector<ba::FeatureTrack> out;
  for (auto& [id, track] : tracks)
    if (track.observations.size() >= 2) out.push_back(std::move(track));
  return out;
}

}  // namespace keel::pipeline
