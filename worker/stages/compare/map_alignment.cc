#include "worker/stages/compare/compare_maps.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/robust_spread.h"
#include "worker/compare/local_registration.h"
#include "worker/compare/stable_registration.h"

namespace keel::pipeline {
namespace {

using nlohmann::json;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

json pose_json(const Pose3& T) {
  const Eigen::Quaterniond q(T.linear());
  return {{"translation_m", {T.translation().x(), T.translation().y(), T.translation().z()}},
          {"rotation_xyzw", {q.x(), q.y(), q.z(), q.w()}},
          {"translation_norm_m", T.translation().norm()},
          {"rotation_deg", Eigen::AngleAxisd(T.linear()).angle() * 180.0 / M_PI}};
}

json registration_json(const compare::StableRegistration& r) {
  return {{"T_a_b", pose_json(r.T_a_b)},
          {"iterations", r.iterations},
          {"converged", r.converged},
          {"samples", r.samples},
          {"correspondences", r.correspondences},
          {"stable_pairs", r.stable},
          {"stable_fraction", r.correspondences ? double(r.stable) / r.correspondences : 0.0},
          {"stable_band_m", r.band_m},
          {"rms_stable_m", r.rms_stable_m},
          {"conditioning", r.conditioning}};
}

// The global registration of B onto A on `map`. The same map on both sides (a job compared
// with itself) is its own registration: the identity, no residual.
void register_globally(StageContext& context, const CompareStageOptions& options,
                       const std::string& map, const std::vector<Eigen::Vector3f>& a,
                       const std::vector<Eigen::Vector3f>& b, MapAlignment* alignment) {
  alignment->registered = true;  // once, whatever the outcome: a failure fails the stage
  if (a == b) {
    alignment->registration = {{"map", map},
                               {"identical_maps", true},
                               {"T_a_b", pose_json(Pose3::Identity())},
                               {"rms_stable_m", 0.0}};
    return;
  }
  const auto t = std::chrono::steady_clock::now();
  compare::StableRegistrationOptions ro = options.registration;
  ro.threads = options.threads;
  ro.check_canceled = [&] { context.check_canceled(); };
  const compare::StableRegistration result = compare::register_stable(a, b, Pose3::Identity(), ro);
  alignment->T_a_b = result.T_a_b;
  alignment->registration = registration_json(result);
  alignment->registration["map"] = map;
  alignment->registration["seconds"] = seconds_since(t);
  context.log("registered B onto A on " + map + ": " +
              std::to_string(result.T_a_b.translation().norm()) + " m, rms " +
              std::to_string(result.rms_stable_m) + " m on " + std::to_string(result.stable) +
              " stable pairs");
}

}  // namespace

json align_map(StageContext& context, const CompareStageOptions& options, const std::string& map,
               const std::vector<Eigen::Vector3f>& a, std::vector<Eigen::Vector3f>* b,
               MapAlignment* alignment) {
  if (options.register_maps && !alignment->registered)
    register_globally(context, options, map, a, *b, alignment);
  if (alignment->registered)
    for (auto& p : *b) p = (alignment->T_a_b * p.cast<double>()).cast<float>();
  if (!options.register_maps || options.local_registration_tile_m <= 0 || a == *b) return nullptr;

  const auto t = std::chrono::steady_clock::now();
  const compare::LocalRegistration local =
      compare::register_tiles(a, b, local_registration_options(context, options));
  std::vector<double> corrections;
  json tiles = json::array();
  for (const compare::TileRegistration& tile : local.tiles) {
    const compare::TileCorrection& c = tile.correction;
    if (c.applied()) corrections.push_back(c.correction_m);
    tiles.push_back({{"center_m", {tile.center_m.x(), tile.center_m.y(), tile.center_m.z()}},
                     {"status", c.status},
                     {"cores", c.cores},
                     {"stable_cores", c.stable},
                     {"noise_m", c.noise_m},
                     {"fixed_directions", c.fixed_directions},
                     {"correction_m", c.applied() ? c.correction_m : 0.0}});
  }
  const RobustSpread shift = robust_spread(corrections);
  context.log(map + ": " + std::to_string(local.adjusted) + " of " +
              std::to_string(local.tiles.size()) + " tiles corrected on their stable structure");
  return {{"tile_m", options.local_registration_tile_m},
          {"tiles", local.tiles.size()},
          {"adjusted_tiles", local.adjusted},
          {"median_correction_m", shift.median},
          {"per_tile", tiles},
          {"seconds", seconds_since(t)}};
}

compare::LocalRegistrationOptions local_registration_options(StageContext& context,
                                                             const CompareStageOptions& options) {
  compare::LocalRegistrationOptions lo;
  lo.tile_m = options.local_registration_tile_m;
  lo.m3c2 = options.m3c2;
  lo.tile = options.tile_correction;
  lo.threads = options.threads;
  lo.check_canceled = [&context] { context.check_canceled(); };
  return lo;
}

}  // namespace keel::pipeline
