#include "worker/ba/ba_result.h"

#include <algorithm>
#include <cmath>

namespace keel::ba {

std::vector<double> residual_values(const std::vector<DvlBeamResidual>& beams) {
  std::vector<double> out;
  out.reserve(beams.size());
  for (const DvlBeamResidual& b : beams) out.push_back(b.residual_m);
  return out;
}

const BaModeResult* BaResult::find(BaMode mode) const {
  const auto it = std::find_if(modes.begin(), modes.end(),
                               [mode](const BaModeResult& r) { return r.mode == mode; });
  return it == modes.end() ? nullptr : &*it;
}

InspectionPoint inspection_point(const BaLandmark& l, double sigmas) {
  const bool rays_disagree = l.lambda == 1 && std::isfinite(l.vision_sigma_m) &&
                             std::abs(l.vision_signed_distance_m) > sigmas * l.vision_sigma_m;
  if (rays_disagree) return {l.vision_position_world, l.vision_signed_distance_m};
  return {l.position_world, l.signed_distance_m};
}

std::vector<CameraFramePoint> landmarks_in_camera(const BaModeResult& result, int keyframe) {
  std::vector<CameraFramePoint> points;
  if (keyframe < 0 || keyframe >= static_cast<int>(result.T_world_camera.size())) return points;
  const Pose3 T_camera_world = result.T_world_camera[keyframe].inverse();
  for (size_t i = 0; i < result.landmarks.size(); ++i) {
    const BaLandmark& l = result.landmarks[i];
    if (std::find(l.keyframes.begin(), l.keyframes.end(), keyframe) == l.keyframes.end()) continue;
    points.push_back({i, T_camera_world * l.position_world, l.signed_distance_m, l.lambda});
  }
  return points;
}

}  // namespace keel::ba
