#include "worker/ba/ba_options.h"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace keel::ba {

const char* to_string(BaMode mode) {
  switch (mode) {
    case BaMode::kNaive:
      return "naive";
    case BaMode::kGeva:
      return "geva";
    case BaMode::kProposed:
      return "proposed";
  }
  return "unknown";
}

BaMode ba_mode_from_string(const std::string& name) {
  if (name == "naive") return BaMode::kNaive;
  if (name == "geva") return BaMode::kGeva;
  if (name == "proposed") return BaMode::kProposed;
  throw std::invalid_argument("ba mode: expected naive, geva or proposed, got '" + name + "'");
}

void validate(const BaOptions& o) {
  const std::pair<const char*, double> positive[] = {
      {"sigma0_m", o.sigma0_m},
      {"sigma1_m", o.sigma1_m},
      {"model_prior_sigma_m", o.model_prior_sigma_m},
      {"model_prior_sigma_rad", o.model_prior_sigma_rad},
      {"first_pose_prior_sigma_m", o.first_pose_prior_sigma_m},
      {"first_pose_prior_sigma_rad", o.first_pose_prior_sigma_rad},
      {"extrinsic_prior_sigma_m", o.extrinsic_prior_sigma_m},
      {"extrinsic_prior_sigma_rad", o.extrinsic_prior_sigma_rad},
      {"depth_sigma_m", o.depth_sigma_m},
      {"pitch_sigma_rad", o.pitch_sigma_rad},
      {"roll_sigma_rad", o.roll_sigma_rad},
      {"servo_sigma_rad", o.servo_sigma_rad},
      {"odometry_sigma_m_per_s", o.odometry_sigma_m_per_s},
      {"odometry_sigma_rad_per_s", o.odometry_sigma_rad_per_s},
      {"odometry_min_sigma_m", o.odometry_min_sigma_m},
      {"odometry_min_sigma_rad", o.odometry_min_sigma_rad},
      {"pixel_sigma", o.pixel_sigma},
      {"reprojection_huber", o.reprojection_huber},
      {"dvl_sigma_m", o.dvl_sigma_m},
      {"dvl_huber", o.dvl_huber},
      {"dvl_gate_m", o.dvl_gate_m},
      {"dvl_max_range_m", o.dvl_max_range_m},
      {"function_tolerance", o.function_tolerance},
      {"gradient_tolerance", o.gradient_tolerance},
      {"parameter_tolerance", o.parameter_tolerance},
      {"frontend.min_depth_m", o.frontend.min_depth_m},
      {"frontend.max_depth_m", o.frontend.max_depth_m},
      {"triangulation.post_initialisation_gate_sigmas",
       o.triangulation.post_initialisation_gate_sigmas},
      {"triangulation.min_pixel_sigma_px", o.triangulation.min_pixel_sigma_px},
  };
  for (const auto& [name, value] : positive) {
    if (!std::isfinite(value) || value <= 0) {
      throw std::invalid_argument(std::string("ba options: ") + name +
                                  ": expected a finite value > 0, got " + std::to_string(value));
    }
  }
  if (!std::isfinite(o.surface_offset_m)) {
    throw std::invalid_argument("ba options: surface_offset_m: expected a finite value");
  }
  if (o.frontend.min_depth_m >= o.frontend.max_depth_m) {
    throw std::invalid_argument(
        "ba options: frontend.max_depth_m: expected more than frontend.min_depth_m");
  }
  if (o.triangulation.min_monocular_views < 2) {
    throw std::invalid_argument("ba options: triangulation.min_monocular_views: expected >= 2");
  }
  if (o.modes.empty()) throw std::invalid_argument("ba options: modes: expected at least one mode");
  if (o.max_iterations < 1 || o.num_threads < 1 || o.initialisation_max_iterations < 1) {
    throw std::invalid_argument(
        "ba options: max_iterations, initialisation_max_iterations and num_threads: expected >= 1");
  }
}

}  // namespace keel::ba
