#include "worker/stages/refine/inputs.h"

#include <algorithm>
#include <stdexcept>

#include "proto/contract_error.h"

namespace keel::pipeline {

Inputs recorded_keyframes(const io::MissionReader& reader) {
  if (!reader.has_trajectory("map"))
    throw std::runtime_error(
        "refine needs the recorded keyframe poses: mission.yaml has no trajectories.map");
  Inputs in;
  in.solver.keyframes = reader.read_trajectory("map");
  const Trajectory& recorded = in.solver.keyframes;
  require_keyframes(recorded, "in trajectories.map");
  in.report["keyframes"] = span_json(recorded.front().t_ns, recorded.back().t_ns);
  in.report["keyframes"]["source"] = "map";
  in.report["keyframes"]["recorded"] = recorded.size();
  return in;
}

const proto::SensorSpec* pick_sensor(const proto::MissionManifest& manifest,
                                     const std::string& chosen, proto::SensorType type,
                                     const std::string& option) {
  if (!chosen.empty()) {
    const proto::SensorSpec* s = manifest.find_sensor(chosen);
    if (!s)
      throw proto::ContractError("options.refine." + option + ": mission has no sensor '" + chosen +
                                 "'");
    if (s->type != type)
      throw proto::ContractError("options.refine." + option + ": sensor '" + chosen + "' is a " +
                                 proto::to_string(s->type) + ", expected " +
                                 proto::to_string(type));
    return s;
  }
  for (const auto& s : manifest.sensors)
    if (s.type == type) return &s;
  return nullptr;
}

nlohmann::json span_json(TimeNs first, TimeNs last) {
  return {{"t_first_s", ns_to_seconds(first)},
          {"t_last_s", ns_to_seconds(last)},
          {"duration_s", ns_to_seconds(last - first)}};
}

long find_keyframe(const Trajectory& keyframes, TimeNs t_ns, TimeNs tolerance) {
  auto it = std::lower_bound(keyframes.begin(), keyframes.end(), t_ns,
                             [](const StampedPose& p, TimeNs t) { return p.t_ns < t; });
  long best = -1;
  TimeNs best_dt = tolerance + 1;
  for (auto c : {it, it == keyframes.begin() ? it : it - 1}) {
    if (c == keyframes.end()) continue;
    const TimeNs dt = std::abs(c->t_ns - t_ns);
    if (dt < best_dt) {
      best_dt = dt;
      best = static_cast<long>(c - keyframes.begin());
    }
  }
  return best;
}

Trajectory select(const Trajectory& keyframes, const std::vector<bool>& keep) {
  Trajectory out;
  for (size_t k = 0; k < keyframes.size(); ++k)
    if (keep[k]) out.push_back(keyframes[k]);
  return out;
}

void require_keyframes(const Trajectory& keyframes, const std::string& why) {
  if (keyframes.size() < 2)
    throw std::runtime_error("refine needs at least 2 keyframes " + why + ", found " +
                             std::to_string(keyframes.size()));
}

}  // namespace keel::pipeline
