// The solver options the stage's options stand for (slam/refine_solver.h); the sensor noise
// figures come from mission.yaml (inertial_inputs.cc).
#include <cmath>

#include "worker/stages/refine/options.h"

namespace keel::pipeline {

slam::RefineOptions RefineStageOptions::solver_options() const {
  slam::RefineOptions s;
  s.use_dvl = dvl;
  s.use_loop_closures = loop_closures;
  s.use_map_anchors = map_anchors;
  s.estimate_map_noise = estimate_map_noise;
  s.map_noise = slam::MapPoseNoise::isotropic(map_sigma_translation_m, map_sigma_rotation_rad,
                                              map_drift_per_sqrt_m);
  s.estimate_dvl_scale = estimate_dvl_scale;
  s.dvl_scale_initial = dvl_scale_initial;
  s.dvl_scale_prior_sigma = dvl_scale_prior_sigma;
  s.estimate_dvl_rotation = estimate_dvl_rotation;
  s.dvl_rotation_prior_sigma_rad = dvl_rotation_prior_sigma_deg * M_PI / 180.0;
  s.reconcile.max_dvl_gap_s = max_dvl_gap_s;
  s.imu_position_when_degenerate = imu_position_when_degenerate;
  s.degeneracy.min_eigenvalue_translation =
      1.0 / (degeneracy_sigma_translation_m * degeneracy_sigma_translation_m);
  s.degeneracy.min_eigenvalue_rotation =
      1.0 / (degeneracy_sigma_rotation_rad * degeneracy_sigma_rotation_rad);
  s.degeneracy_handling = degeneracy == "ignore" ? slam::DegeneracyHandling::kIgnore
                          : degeneracy == "keep_well_conditioned"
                              ? slam::DegeneracyHandling::kKeepWellConditioned
                              : slam::DegeneracyHandling::kDropFactor;
  s.gnss.gate_chi2 = gnss_gate_chi2;
  s.max_iterations = max_iterations;
  s.relinearization_passes = relinearization_passes;
  s.num_threads = threads;
  return s;
}

}  // namespace keel::pipeline
